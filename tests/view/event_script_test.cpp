// SPDX-License-Identifier: Apache-2.0
// Event scripts: to_json → parse keeps every field, save → load too; malformed scripts are
// refused with the file and the JSON pointer of the bad field.
#include "ido/view/event_script.h"

#include <fstream>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "support/test_support.h"

namespace ido {
namespace {

namespace fs = std::filesystem;

using view::EventKind;

TEST(EventScript, RoundTripKeepsEveryField) {
  view::EventScript s;
  s.window_width_px = 900;
  s.window_height_px = 600;
  auto add = [&](std::int64_t frame, EventKind kind) -> view::InputEvent& {
    view::InputEvent e;
    e.frame = frame;
    e.kind = kind;
    s.events.push_back(e);
    return s.events.back();
  };
  add(1, EventKind::MouseMove).x_px = 10.5;
  s.events.back().y_px = 20.25;
  auto& down = add(2, EventKind::MouseDown);
  down.x_px = 11;
  down.y_px = 21;
  down.button = 1;
  down.shift = true;  // a shift-click (a stop point on a slice)
  auto& up = add(3, EventKind::MouseUp);
  up.x_px = 12;
  up.y_px = 22;
  up.button = 1;
  auto& scroll = add(3, EventKind::Scroll);
  scroll.x_px = 5;
  scroll.scroll_y = -2;
  auto& key = add(4, EventKind::KeyDown);
  key.key = "s";
  key.ctrl = true;
  key.alt = true;
  add(5, EventKind::KeyUp).key = "s";
  add(5, EventKind::Char).codepoint = 0x41;
  auto& wait = add(6, EventKind::Wait);
  wait.until = "segment_done";
  wait.timeout_s = 30;
  auto& steps = add(6, EventKind::Wait);
  steps.until = "deform_steps";
  steps.steps = 250;
  add(7, EventKind::Screenshot).name = "a.png";
  add(8, EventKind::Quit);
  const view::EventScript back = view::EventScript::parse(s.to_json(), "test");
  EXPECT_EQ(back.window_width_px, 900);
  EXPECT_EQ(back.window_height_px, 600);
  ASSERT_EQ(back.events.size(), s.events.size());
  for (std::size_t i = 0; i < s.events.size(); ++i) {
    const auto &a = s.events[i], &b = back.events[i];
    EXPECT_EQ(a.frame, b.frame);
    EXPECT_EQ(a.kind, b.kind) << i;
    EXPECT_EQ(a.x_px, b.x_px);
    EXPECT_EQ(a.y_px, b.y_px);
    EXPECT_EQ(a.button, b.button);
    EXPECT_EQ(a.scroll_y, b.scroll_y);
    EXPECT_EQ(a.key, b.key);
    EXPECT_EQ(a.ctrl, b.ctrl);
    EXPECT_EQ(a.shift, b.shift) << i;
    EXPECT_EQ(a.alt, b.alt) << i;
    EXPECT_EQ(a.codepoint, b.codepoint);
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.until, b.until);
    EXPECT_EQ(a.steps, b.steps);
    EXPECT_EQ(a.timeout_s, b.timeout_s);
  }
}

TEST(EventScript, MalformedScriptsNameTheEvent) {
  auto message = [](const std::string& text) -> std::string {
    try {
      (void)view::EventScript::parse(text, "s.json");
    } catch (const Error& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_NE(message("{\"events\": [{\"frame\": 1, \"type\": \"fly\"}]}").find("/events/0/type"), std::string::npos);
  EXPECT_NE(message("{\"events\": [{\"frame\": 3, \"type\": \"quit\"}, {\"frame\": 2, \"type\": \"quit\"}]}")
                .find("/events/1/frame"),
            std::string::npos);
  EXPECT_NE(message("{\"events\": [{\"frame\": 1, \"type\": \"mouse_down\", \"button\": \"fourth\"}]}").find("button"),
            std::string::npos);
  EXPECT_NE(message("{\"events\": [{\"frame\": 1, \"type\": \"screenshot\", \"name\": \"../x.png\"}]}").find("name"),
            std::string::npos);
  EXPECT_NE(message("{\"window\": [10, 10], \"events\": []}").find("/window"), std::string::npos);
  EXPECT_NE(message("{\"events\": [").find("s.json"), std::string::npos);
  EXPECT_NE(message("{\"events\": [{\"frame\": 1, \"type\": \"key_down\", \"key\": \"a\", \"ctrl\": 1}]}").find("/events/0/ctrl"),
            std::string::npos);
  EXPECT_EQ(message("{\"events\": []}"), "accepted");
}

// The message of parsing @p text as "s.json", or "accepted".
std::string parse_message(const std::string& text) {
  try {
    (void)view::EventScript::parse(text, "s.json");
  } catch (const Error& e) {
    return e.what();
  }
  return "accepted";
}

TEST(EventScript, EveryBadFieldIsNamedByItsPointerAndTheFile) {
  struct Case {
    const char* json;
    const char* pointer;
  };
  const Case cases[] = {
      {R"({"events": [{"frame": -1, "type": "quit"}]})", "/events/0/frame"},
      {R"({"events": [{"frame": 1.5, "type": "quit"}]})", "/events/0/frame"},
      {R"({"events": [{"type": "quit"}]})", "/events/0/frame"},
      {R"({"events": [{"frame": 0, "type": "quit"}, {"frame": 1, "type": 3}]})", "/events/1/type"},
      {R"({"events": [{"frame": 0, "type": "mouse_move", "x": "10"}]})", "/events/0/x"},
      {R"({"events": [{"frame": 0, "type": "scroll", "dy": null}]})", "/events/0/dy"},
      {R"({"events": [{"frame": 0, "type": "key_down"}]})", "/events/0/key"},
      {R"({"events": [{"frame": 0, "type": "key_up", "key": ""}]})", "/events/0/key"},
      {R"({"events": [{"frame": 0, "type": "char", "codepoint": 0}]})", "/events/0/codepoint"},
      {R"({"events": [{"frame": 0, "type": "char", "codepoint": 1114112}]})", "/events/0/codepoint"},
      {R"({"events": [{"frame": 0, "type": "char", "codepoint": 65.5}]})", "/events/0/codepoint"},
      {R"({"events": [{"frame": 0, "type": "screenshot"}]})", "/events/0/name"},
      {R"({"events": [{"frame": 0, "type": "screenshot", "name": "shots/a.png"}]})", "/events/0/name"},
      {R"({"events": [{"frame": 0, "type": "wait", "until": "lunch"}]})", "/events/0/until"},
      {R"({"events": [{"frame": 0, "type": "wait", "until": "deform_steps"}]})", "/events/0/steps"},
      {R"({"events": [{"frame": 0, "type": "wait", "until": "deform_steps", "steps": 0}]})", "/events/0/steps"},
      {R"({"events": [{"frame": 0, "type": "wait", "until": "idle", "timeout": 0}]})", "/events/0/timeout"},
      {R"({"events": [{"frame": 0, "type": "mouse_up", "button": "left", "alt": "yes"}]})", "/events/0/alt"},
      {R"({"events": [7]})", "/events/0"},
      {R"({"window": [800], "events": []})", "/window"},
      {R"({"window": [63, 600], "events": []})", "/window"},
      {R"({"window": [800, 8193], "events": []})", "/window"},
      {R"({"window": [4294968296, 800], "events": []})", "/window"},
      {R"({"window": [800.5, 600], "events": []})", "/window"},
      {R"({"events": {}})", "/events"},
      {R"({"window": [800, 600]})", "/events"},
      {R"([1, 2])", "/"},
  };
  for (const Case& c : cases) {
    const std::string m = parse_message(c.json);
    EXPECT_EQ(m.rfind("s.json: ", 0), 0U) << c.json << " -> " << m;
    EXPECT_NE(m.find(std::string(c.pointer) + ":"), std::string::npos) << c.json << " -> " << m;
  }
  // The bad value itself is quoted where it is a name.
  EXPECT_NE(parse_message(R"({"events": [{"frame": 0, "type": "fly"}]})").find("'fly'"), std::string::npos);
  EXPECT_NE(parse_message(R"({"events": [{"frame": 0, "type": "mouse_down", "button": "fourth"}]})").find("'fourth'"),
            std::string::npos);
  EXPECT_NE(parse_message(R"({"events": [{"frame": 0, "type": "wait", "until": "lunch"}]})").find("'lunch'"), std::string::npos);
  // Boundaries that are fine.
  EXPECT_EQ(parse_message(R"({"window": [64, 8192], "events": [{"frame": 0, "type": "char", "codepoint": 1114111}]})"),
            "accepted");
}

TEST(EventScript, DefaultsForKeysAnEventLeavesOut) {
  const auto s = view::EventScript::parse(
      R"({"events": [{"frame": 0, "type": "mouse_down"}, {"frame": 0, "type": "wait", "until": "idle"},
                     {"frame": 2, "type": "scroll"}]})",
      "d.json");
  EXPECT_EQ(s.window_width_px, 1280);
  EXPECT_EQ(s.window_height_px, 800);
  ASSERT_EQ(s.events.size(), 3U);
  EXPECT_EQ(s.events[0].button, 0) << "left by default";
  EXPECT_EQ(s.events[0].x_px, 0.0);
  EXPECT_FALSE(s.events[0].ctrl || s.events[0].shift || s.events[0].alt);
  EXPECT_EQ(s.events[1].timeout_s, 60.0);
  EXPECT_EQ(s.events[2].scroll_y, 0.0);
}

TEST(EventScript, KindNamesAreDistinctAndParseBack) {
  std::set<std::string> names;
  for (int k = 0; k <= static_cast<int>(EventKind::Quit); ++k) {
    const auto kind = static_cast<EventKind>(k);
    const std::string name = view::event_kind_name(kind);
    EXPECT_TRUE(names.insert(name).second) << name;
    // A one-event script of that kind, with the fields the kind needs, reads back as the kind.
    view::EventScript s;
    view::InputEvent e;
    e.kind = kind;
    e.key = "a";
    e.codepoint = 0x263A;
    e.name = "x.png";
    e.until = "idle";
    s.events.push_back(e);
    const auto back = view::EventScript::parse(s.to_json(), name);
    ASSERT_EQ(back.events.size(), 1U);
    EXPECT_EQ(back.events[0].kind, kind) << name;
  }
  EXPECT_EQ(names.size(), 10U);
  EXPECT_STREQ(view::event_kind_name(EventKind::MouseMove), "mouse_move");
  EXPECT_STREQ(view::event_kind_name(EventKind::Quit), "quit");
}

TEST(EventScript, SaveThenLoadAndUnreadableFiles) {
  const fs::path dir = test::scratch_dir("event_script_files");
  view::EventScript s;
  s.window_width_px = 640;
  s.window_height_px = 480;
  view::InputEvent e;
  e.frame = 12;
  e.kind = EventKind::MouseMove;
  e.x_px = 1.0 / 3.0;  // doubles survive the text exactly
  e.y_px = 479.75;
  s.events.push_back(e);
  s.save(dir / "s.json");
  const auto back = view::EventScript::load(dir / "s.json");
  EXPECT_EQ(back.window_width_px, 640);
  EXPECT_EQ(back.window_height_px, 480);
  ASSERT_EQ(back.events.size(), 1U);
  EXPECT_EQ(back.events[0].frame, 12);
  EXPECT_EQ(back.events[0].x_px, 1.0 / 3.0);
  EXPECT_EQ(back.events[0].y_px, 479.75);
  try {
    (void)view::EventScript::load(dir / "absent.json");
    FAIL() << "a missing file loaded";
  } catch (const IoError& err) {
    EXPECT_EQ(err.path(), (dir / "absent.json").string());
  }
  std::ofstream(dir / "broken.json") << "{\"events\": [";
  try {
    (void)view::EventScript::load(dir / "broken.json");
    FAIL() << "broken JSON loaded";
  } catch (const IoError& err) {
    EXPECT_EQ(err.path(), (dir / "broken.json").string());
  }
  std::ofstream(dir / "invalid.json") << R"({"events": [{"frame": 0, "type": "fly"}]})";
  try {
    (void)view::EventScript::load(dir / "invalid.json");
    FAIL() << "an unknown type loaded";
  } catch (const InvalidInput& err) {
    EXPECT_NE(std::string(err.what()).find((dir / "invalid.json").string()), std::string::npos) << err.what();
  }
}

}  // namespace
}  // namespace ido
