// SPDX-License-Identifier: Apache-2.0
// The library's logger: silent by default, replaced by the caller's, restored by nullptr.
#include "ido/core/log.h"

#include <memory>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>
#include <spdlog/sinks/ostream_sink.h>

namespace ido {
namespace {

// A logger writing "level: message" lines to @p out.
std::shared_ptr<spdlog::logger> capturing(std::ostringstream& out) {
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(out);
  sink->set_pattern("%l: %v");
  auto l = std::make_shared<spdlog::logger>("capture", sink);
  l->set_level(spdlog::level::trace);
  return l;
}

TEST(Log, InstalledLoggerReceivesTheLibrarysMessagesAndNullptrSilencesIt) {
  std::ostringstream out;
  const auto mine = capturing(out);
  set_logger(mine);
  EXPECT_EQ(&logger(), mine.get()) << "logger() is the installed one, not a copy";
  logger().warn("seed {} outside the volume", 3);
  logger().debug("step {}", 7);
  logger().flush();
  EXPECT_EQ(out.str(), "warning: seed 3 outside the volume\ndebug: step 7\n");

  // The caller keeps a handle and changes the level: the library's messages follow it.
  mine->set_level(spdlog::level::warn);
  logger().info("not shown");
  logger().error("shown");
  logger().flush();
  EXPECT_EQ(out.str(), "warning: seed 3 outside the volume\ndebug: step 7\nerror: shown\n");

  // nullptr restores the silent default: nothing more reaches the caller's sink.
  set_logger(nullptr);
  EXPECT_NE(&logger(), mine.get());
  logger().error("after reset");
  logger().flush();
  EXPECT_EQ(out.str().find("after reset"), std::string::npos);
}

TEST(Log, DefaultLoggerHasNoSinkThatPrints) {
  set_logger(nullptr);
  // Whatever it holds, every sink is a null sink: the library prints nothing by default.
  for (const auto& sink : logger().sinks()) {
    EXPECT_NE(dynamic_cast<spdlog::sinks::null_sink_mt*>(sink.get()), nullptr);
  }
  // Replacing the default twice keeps the last one.
  std::ostringstream a, b;
  set_logger(capturing(a));
  set_logger(capturing(b));
  logger().warn("to b");
  logger().flush();
  EXPECT_TRUE(a.str().empty());
  EXPECT_EQ(b.str(), "warning: to b\n");
  set_logger(nullptr);
}

}  // namespace
}  // namespace ido
