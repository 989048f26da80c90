// SPDX-License-Identifier: Apache-2.0
// Repeated warnings are written once per kind per interval of simulated time, with a count of
// those held back; a world refusing a team's commands 100 times a second writes one line a second.
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "../../common/test_world.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/world.hpp"
#include "world/repeated_warnings.hpp"

namespace ubersim::kernel {
namespace {

int Lines(const std::string& text) {
  int n = 0;
  for (char c : text) n += c == '\n';
  return n;
}

TEST(RepeatedWarnings, OneLinePerKindPerIntervalWithTheCountHeldBack) {
  std::ostringstream text;
  StreamLog log(text, LogLevel::kWarning);
  RepeatedWarnings warnings(log, 1'000'000'000);
  for (int i = 0; i < 50; ++i) warnings.Warn("refused blue 3", "refused " + std::to_string(i), i * 10'000'000);
  EXPECT_EQ(Lines(text.str()), 1) << text.str();  // 0.49 s: the first line only
  warnings.Warn("refused blue 4", "refused other", 500'000'000);  // another kind: at once
  EXPECT_EQ(Lines(text.str()), 2) << text.str();
  warnings.Warn("refused blue 3", "refused again", 1'000'000'000);
  EXPECT_EQ(Lines(text.str()), 3) << text.str();
  EXPECT_NE(text.str().find("refused again (and 49 more like it held back since the last line)"), std::string::npos)
      << text.str();
  warnings.Clear();  // a reset: time starts again, the next is written at once
  warnings.Warn("refused blue 3", "after reset", 0);
  EXPECT_NE(text.str().find("after reset\n"), std::string::npos) << text.str();
}

TEST(RepeatedWarnings, AWorldRefusingCommandsForARobotNotThereWritesOneLineASecond) {
  std::ostringstream text;
  StreamLog log(text, LogLevel::kWarning);
  PluginRegistry registry({});
  World world(testing::BallWorld(Vec3(0, 0, 0)), registry, log, false);
  for (int step = 0; step < 1500; ++step) {
    if (step % 10 == 0) world.events().Post(CommandEvent{{Team::kBlue, 9}, LocalVelocityCommand{1.0, 0.0, 0.0}, {}, {}});
    world.Step();
  }
  // 150 commands over 1.5 s: a line at 0 s and one at 1.0 s saying 99 were held back.
  EXPECT_EQ(Lines(text.str()), 2) << text.str();
  EXPECT_NE(text.str().find("command for unknown robot blue 9 ignored (and 99 more like it"), std::string::npos)
      << text.str();
  EXPECT_EQ(world.event_counters().rejected, 150);
}

}  // namespace
}  // namespace ubersim::kernel
