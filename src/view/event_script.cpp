// SPDX-License-Identifier: Apache-2.0
#include "ido/view/event_script.h"

#include <array>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string_view>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "ido/core/atomic_file.h"
#include "ido/core/error.h"

namespace ido::view {
namespace {

constexpr std::array<std::pair<EventKind, const char*>, 10> kKindNames = {{
    {EventKind::MouseMove, "mouse_move"},
    {EventKind::MouseDown, "mouse_down"},
    {EventKind::MouseUp, "mouse_up"},
    {EventKind::Scroll, "scroll"},
    {EventKind::KeyDown, "key_down"},
    {EventKind::KeyUp, "key_up"},
    {EventKind::Char, "char"},
    {EventKind::Screenshot, "screenshot"},
    {EventKind::Wait, "wait"},
    {EventKind::Quit, "quit"},
}};
constexpr std::array<const char*, 3> kButtonNames = {"left", "right", "middle"};

bool is_mouse(EventKind k) {
  return k == EventKind::MouseMove || k == EventKind::MouseDown || k == EventKind::MouseUp || k == EventKind::Scroll;
}

/// Key and button events carry the modifiers held (a shift-click places a stop point).
bool has_modifiers(EventKind k) {
  return k == EventKind::KeyDown || k == EventKind::KeyUp || k == EventKind::MouseDown || k == EventKind::MouseUp;
}

}  // namespace

const char* event_kind_name(EventKind kind) noexcept {
  for (const auto& [k, name] : kKindNames)
    if (k == kind) return name;
  return "?";
}

EventScript EventScript::parse(const std::string& json_text, const std::string& source_name) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::parse_error& e) {
    throw IoError(source_name, fmt::format("not JSON: {}", e.what()), {.line = std::nullopt, .byte_offset = std::int64_t(e.byte)});
  }
  auto bad = [&](const std::string& where, const std::string& what) {
    return InvalidInput(fmt::format("{}: {}: {}", source_name, where, what));
  };
  if (!j.is_object()) throw bad("/", "expected an object with \"events\"");
  EventScript s;
  if (j.contains("window")) {
    const auto& w = j["window"];
    if (!w.is_array() || w.size() != 2 || !w[0].is_number_integer() || !w[1].is_number_integer())
      throw bad("/window", "expected [WIDTH, HEIGHT] in pixels");
    // Checked at 64 bits: get<int>() would wrap a size like 4294968296 into the range.
    const auto width = w[0].get<std::int64_t>(), height = w[1].get<std::int64_t>();
    if (width < 64 || width > 8192 || height < 64 || height > 8192)
      throw bad("/window", "each side must be 64..8192 pixels");
    s.window_width_px = static_cast<int>(width);
    s.window_height_px = static_cast<int>(height);
  }
  if (!j.contains("events") || !j["events"].is_array()) throw bad("/events", "expected an array of events");
  std::int64_t last_frame = 0;
  for (std::size_t n = 0; n < j["events"].size(); ++n) {
    const auto& e = j["events"][n];
    const std::string where = fmt::format("/events/{}", n);
    if (!e.is_object()) throw bad(where, "expected an object");
    auto number = [&](const char* key, double fallback) {
      if (!e.contains(key)) return fallback;
      if (!e[key].is_number() || !std::isfinite(e[key].get<double>()))
        throw bad(where + "/" + key, "expected a finite number");
      return e[key].get<double>();
    };
    auto text = [&](const char* key) {
      if (!e.contains(key)) return std::string();
      if (!e[key].is_string()) throw bad(where + "/" + key, "expected a string");
      return e[key].get<std::string>();
    };
    InputEvent ev;
    if (!e.contains("frame") || !e["frame"].is_number_integer()) throw bad(where + "/frame", "expected an integer frame");
    ev.frame = e["frame"].get<std::int64_t>();
    if (ev.frame < 0) throw bad(where + "/frame", "must be 0 or more");
    if (ev.frame < last_frame) throw bad(where + "/frame", "frames must not decrease");
    last_frame = ev.frame;
    const std::string type = text("type");
    bool known = false;
    for (const auto& [k, name] : kKindNames)
      if (type == name) {
        ev.kind = k;
        known = true;
      }
    if (!known) throw bad(where + "/type", fmt::format("unknown event type '{}'", type));
    if (is_mouse(ev.kind)) {
      ev.x_px = number("x", 0.0);
      ev.y_px = number("y", 0.0);
    }
    if (ev.kind == EventKind::MouseDown || ev.kind == EventKind::MouseUp) {
      const std::string b = e.contains("button") ? text("button") : "left";
      ev.button = -1;
      for (int i = 0; i < 3; ++i)
        if (b == kButtonNames[std::size_t(i)]) ev.button = i;
      if (ev.button < 0) throw bad(where + "/button", fmt::format("'{}': expected left, right or middle", b));
    }
    if (ev.kind == EventKind::Scroll) ev.scroll_y = number("dy", 0.0);
    if (ev.kind == EventKind::KeyDown || ev.kind == EventKind::KeyUp) {
      ev.key = text("key");
      if (ev.key.empty()) throw bad(where + "/key", "expected a key name");
    }
    if (has_modifiers(ev.kind)) {
      auto flag = [&](const char* name) {
        if (!e.contains(name)) return false;
        if (!e[name].is_boolean()) throw bad(where + "/" + name, "expected true or false");
        return e[name].get<bool>();
      };
      ev.ctrl = flag("ctrl");
      ev.shift = flag("shift");
      ev.alt = flag("alt");
    }
    if (ev.kind == EventKind::Char) {
      const double c = number("codepoint", -1);
      if (c < 1 || c > 0x10FFFF || c != std::floor(c)) throw bad(where + "/codepoint", "expected a Unicode code point");
      ev.codepoint = static_cast<std::uint32_t>(c);
    }
    if (ev.kind == EventKind::Screenshot) {
      ev.name = text("name");
      if (ev.name.empty() || ev.name.find('/') != std::string::npos || ev.name.find("..") != std::string::npos)
        throw bad(where + "/name", "expected a plain file name (no folders)");
    }
    if (ev.kind == EventKind::Wait) {
      ev.until = text("until");
      if (ev.until != "idle" && ev.until != "segment_done" && ev.until != "deform_steps")
        throw bad(where + "/until", fmt::format("'{}': expected idle, segment_done or deform_steps", ev.until));
      if (ev.until == "deform_steps") {
        if (!e.contains("steps") || !e["steps"].is_number_integer() || e["steps"].get<std::int64_t>() < 1)
          throw bad(where + "/steps", "expected a number of steps (1 or more)");
        ev.steps = e["steps"].get<std::int64_t>();
      }
      ev.timeout_s = number("timeout", 60.0);
      if (!(ev.timeout_s > 0)) throw bad(where + "/timeout", "must be positive (seconds)");
    }
    s.events.push_back(std::move(ev));
  }
  return s;
}

EventScript EventScript::load(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string(), "cannot open the event script");
  std::stringstream text;
  text << in.rdbuf();
  if (in.bad()) throw IoError(path.string(), "cannot read the event script");
  return parse(text.str(), path.string());
}

std::string EventScript::to_json() const {
  nlohmann::json events = nlohmann::json::array();
  for (const InputEvent& ev : this->events) {
    nlohmann::json e = {{"frame", ev.frame}, {"type", event_kind_name(ev.kind)}};
    if (is_mouse(ev.kind)) {
      e["x"] = ev.x_px;
      e["y"] = ev.y_px;
    }
    if (ev.kind == EventKind::MouseDown || ev.kind == EventKind::MouseUp)
      e["button"] = kButtonNames[std::size_t(std::clamp(ev.button, 0, 2))];
    if (ev.kind == EventKind::Scroll) e["dy"] = ev.scroll_y;
    if (ev.kind == EventKind::KeyDown || ev.kind == EventKind::KeyUp) e["key"] = ev.key;
    if (has_modifiers(ev.kind)) {
      if (ev.ctrl) e["ctrl"] = true;
      if (ev.shift) e["shift"] = true;
      if (ev.alt) e["alt"] = true;
    }
    if (ev.kind == EventKind::Char) e["codepoint"] = ev.codepoint;
    if (ev.kind == EventKind::Screenshot) e["name"] = ev.name;
    if (ev.kind == EventKind::Wait) {
      e["until"] = ev.until;
      if (ev.until == "deform_steps") e["steps"] = ev.steps;
      e["timeout"] = ev.timeout_s;
    }
    events.push_back(std::move(e));
  }
  const nlohmann::json j = {{"window", {window_width_px, window_height_px}}, {"events", events}};
  return j.dump(1) + "\n";
}

void EventScript::save(const std::filesystem::path& path) const {
  const std::string text = to_json();
  write_file_atomically(path, [&](std::ostream& out) { out << text; }, false);
}

}  // namespace ido::view
