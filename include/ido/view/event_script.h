// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ido::view {

/// What an input event of the workbench does.
enum class EventKind {
  MouseMove,   ///< the cursor moves to (x_px, y_px)
  MouseDown,   ///< a button is pressed at (x_px, y_px) (ctrl / shift / alt held)
  MouseUp,     ///< a button is released at (x_px, y_px)
  Scroll,      ///< the wheel turns by scroll_y notches (positive: away from the user) at (x_px, y_px)
  KeyDown,     ///< a key is pressed (key, ctrl / shift / alt held)
  KeyUp,       ///< a key is released
  Char,        ///< a character is typed (codepoint), for text fields
  Screenshot,  ///< scripts only: the frame is written as a PNG named `name`
  Wait,        ///< scripts only: the script stops advancing until `until` holds (or timeout_s)
  Quit,        ///< scripts only: the workbench closes
};

/// The JSON name of @p kind ("mouse_move", "mouse_down", …, "quit").
[[nodiscard]] const char* event_kind_name(EventKind kind) noexcept;

/// One input event, or a script instruction, taking effect at script frame `frame`.
/// Positions are window pixels with (0, 0) the top-left corner.
struct InputEvent {
  std::int64_t frame = 0;  ///< script frame (counted from 0, not advancing while waiting)
  EventKind kind = EventKind::MouseMove;
  double x_px = 0.0, y_px = 0.0;  ///< cursor position (mouse events and scroll)
  int button = 0;                 ///< 0 left, 1 right, 2 middle
  double scroll_y = 0.0;          ///< wheel notches (Scroll)
  std::string key;                ///< key name (KeyDown / KeyUp): "a".."z", "0".."9", "space", "enter", ...
  bool ctrl = false, shift = false, alt = false;  ///< modifiers held (key and button events)
  std::uint32_t codepoint = 0;    ///< Char
  std::string name;               ///< Screenshot: file name inside the screenshot folder
  std::string until;              ///< Wait: "idle" (no work running), "segment_done" or "deform_steps"
  std::int64_t steps = 0;         ///< Wait "deform_steps": this many more scene steps (≥ 1)
  double timeout_s = 60.0;        ///< Wait: wall-clock limit, after which the run fails
};

/// A recorded or hand-written session: the window size it was made for and its events in
/// frame order. The file is JSON:
/// `{"window": [W, H], "events": [{"frame": 3, "type": "mouse_down", "x": 10, "y": 20, "button": "left"}, …]}`;
/// keys that an event's type does not use may be left out (docs/viewer.md lists them).
struct EventScript {
  int window_width_px = 1280;
  int window_height_px = 800;
  std::vector<InputEvent> events;

  /// Reads a script. @throws ido::IoError when the file cannot be read or is not JSON;
  /// ido::InvalidInput naming the file and the event index for an unknown type, button or
  /// key field, a negative frame, frames out of order or a window size outside 64..8192.
  [[nodiscard]] static EventScript load(const std::filesystem::path& path);
  /// Parses script text; @p source_name prefixes messages. @throws as load().
  [[nodiscard]] static EventScript parse(const std::string& json_text, const std::string& source_name);
  /// The script as JSON text (parse() reads it back to an equal script).
  [[nodiscard]] std::string to_json() const;
  /// Writes to_json() atomically. @throws ido::IoError when the file cannot be written.
  void save(const std::filesystem::path& path) const;
};

}  // namespace ido::view
