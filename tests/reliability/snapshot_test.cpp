// SPDX-License-Identifier: Apache-2.0
// Snapshots: step N, save, step M (digest D1); restore into a fresh world, step M (digest D2):
// D1 == D2 bit for bit on the shipped worlds, with robots driving, dribbling and kicking, the
// ball teleported, a robot taken off and put back, vision noise and radio loss; also after a
// reset, from step 0 and on every broadphase. Then the refusals: another world, an edited one,
// and truncated, corrupt or foreign files, each a clear error naming the file and the reason.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <unistd.h>

#include "../common/shipped_worlds.hpp"
#include "../common/test_world.hpp"
#include "ubersim/state_io.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/snapshot.hpp"
#include "ubersim/kernel/world.hpp"

namespace ubersim::kernel {
namespace {

namespace fs = std::filesystem;

using Worlds = testing::ShippedWorlds;

// The same events in both runs, as a function of the step and the world's own state: every
// robot driven at 100 Hz (varying local velocities), dribblers switched, a kick every half second,
// the ball put in front of a robot now and then, and one robot taken off the field for a while.
void Play(World& world, std::int64_t step) {
  const WorldSnapshot now = world.GroundTruth();
  const auto n = static_cast<std::int64_t>(now.robots.size());
  const double t = 1e-3 * static_cast<double>(step);
  if (step % 10 == 0) {
    for (std::int64_t i = 0; i < n; ++i) {
      CommandEvent c;
      c.robot = now.robots[static_cast<std::size_t>(i)].id;
      const double k = static_cast<double>(i);
      c.move = LocalVelocityCommand{0.8 * std::sin(0.5 * t + k), 0.5 * std::cos(0.7 * t + 2 * k),
                                    1.5 * std::sin(0.3 * t + k)};
      c.dribbler_speed = ((step / 1000 + i) % 2) ? 120.0 : 0.0;
      if (step % 500 == 0 && (step / 500) % n == i) c.kick = KickCommand{4.0, (step / 500) % 2 ? 0.5 : 0.0};
      world.events().Post(c);
    }
  }
  if (step % 700 == 350 && n > 0) {
    const RobotState& r = now.robots[static_cast<std::size_t>((step / 700) % n)];
    const Vec3 ahead = r.pose.orientation * Vec3(0.12, 0, 0);
    world.events().Post(PositionEvent{Target::Ball(), r.pose.position + Vec3(ahead.x(), ahead.y(), 0.0),
                                      std::nullopt, Vec3(-0.3 * ahead.x(), -0.3 * ahead.y(), 0), std::nullopt,
                                      std::nullopt});
  }
  if (n > 1 && step % 1100 == 600) {
    PositionEvent e;
    e.target = Target::Robot(now.robots[1].id);
    e.present = (step / 1100) % 2 == 1;
    world.events().Post(e);
  }
}

// Steps `count` steps with Play, folding every body's state, every robot's reported state and
// every vision frame into one digest.
std::uint64_t StepAndDigest(World& world, int count) {
  std::uint64_t digest = 1469598103934665603ULL;
  auto mix = [&](const void* data, std::size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) {
      digest ^= p[i];
      digest *= 1099511628211ULL;
    }
  };
  world.SetVisionObserver([&](const VisionFrame& f) {
    mix(&f.camera_id, sizeof f.camera_id);
    mix(&f.frame_number, sizeof f.frame_number);
    mix(&f.t_sent_ns, sizeof f.t_sent_ns);
    for (const DetectedBall& b : f.balls) mix(&b.x, 2 * sizeof(double));
    for (const DetectedRobot& r : f.robots) {
      mix(&r.x, sizeof r.x);
      mix(&r.y, sizeof r.y);
      mix(&r.yaw, sizeof r.yaw);
    }
  });
  for (int i = 0; i < count; ++i) {
    Play(world, world.clock().steps());
    world.Step();
    const std::uint64_t h = world.StateHash();
    mix(&h, sizeof h);
    for (const RobotState& r : world.GroundTruth().robots) {
      const bool flags[] = {r.present, r.dribbler_ball_contact, r.kicker_ready};
      mix(flags, sizeof flags);
    }
  }
  world.SetVisionObserver(nullptr);
  return digest;
}

struct RoundTrip {
  std::uint64_t original = 0, restored = 0;
  std::size_t bytes = 0;
};

// Runs `before` steps (after `reset_after` steps and a reset, when > 0), saves through the file
// format, runs `after` more; restores into a new world and runs the same `after`.
RoundTrip SaveStepRestoreStep(Worlds& s, const WorldModel& model, int before, int after, int reset_after = 0) {
  RoundTrip r;
  std::string bytes;
  {
    World world(model, s.registry, s.log, false);
    if (reset_after > 0) {
      StepAndDigest(world, reset_after);
      world.Reset();
    }
    StepAndDigest(world, before);
    bytes = EncodeSnapshot(world.Save());
    r.original = StepAndDigest(world, after);
  }
  r.bytes = bytes.size();
  World world(model, s.registry, s.log, false);
  world.Restore(DecodeSnapshot(bytes, "memory"));
  r.restored = StepAndDigest(world, after);
  return r;
}

class ShippedWorld : public ::testing::TestWithParam<const char*> {};

TEST_P(ShippedWorld, RestoredRunIsBitIdenticalToTheOriginal) {
  Worlds s;
  const WorldModel model = s.Load(GetParam());
  const RoundTrip r = SaveStepRestoreStep(s, model, 1700, 1500);
  EXPECT_EQ(r.original, r.restored);
  EXPECT_GT(r.bytes, 1000u);
  // The digest sees the state: a run that goes on from one step later differs.
  World other(model, s.registry, s.log, false);
  StepAndDigest(other, 1701);
  EXPECT_NE(StepAndDigest(other, 1500), r.original);
  EXPECT_EQ(s.log.count(LogLevel::kError), 0) << s.text.str();
}

TEST_P(ShippedWorld, RestoredRunIsBitIdenticalAfterAReset) {
  Worlds s;
  const RoundTrip r = SaveStepRestoreStep(s, s.Load(GetParam()), 900, 1200, 700);
  EXPECT_EQ(r.original, r.restored);
}

TEST_P(ShippedWorld, RestoredRunIsBitIdenticalFromStepZero) {
  Worlds s;
  const RoundTrip r = SaveStepRestoreStep(s, s.Load(GetParam()), 0, 1000);
  EXPECT_EQ(r.original, r.restored);
}

INSTANTIATE_TEST_SUITE_P(Snapshot, ShippedWorld, ::testing::Values("ssl-2003", "div-b", "div-a"));

class Broadphase : public ::testing::TestWithParam<const char*> {};

TEST_P(Broadphase, RestoredRunIsBitIdentical) {
  Worlds s;
  const RoundTrip r = SaveStepRestoreStep(s, s.Load("div-b", GetParam()), 1300, 1500);
  EXPECT_EQ(r.original, r.restored);
}

// The fast settings: 5 ms, the ball's islands at 10 iterations and the others at 4 (two
// QuickStep passes a step, which islands go in which decided from the state alone).
TEST(Snapshot, RestoredRunWithFewerIterationsAwayFromTheBallIsBitIdentical) {
  Worlds s;
  WorldModel model = s.Load("div-b", "sap");
  model.physics.step = 0.005;
  model.physics.solver_iterations = 10;
  model.physics.solver_iterations_without_ball = 4;
  const RoundTrip r = SaveStepRestoreStep(s, model, 300, 400);
  EXPECT_EQ(r.original, r.restored);

  WorldModel same_iterations = model;
  same_iterations.physics.solver_iterations_without_ball.reset();
  const RoundTrip q = SaveStepRestoreStep(s, same_iterations, 300, 400);
  EXPECT_NE(q.original, r.original) << "the setting must change the run, or this test checks nothing new";
}

// A scrum: every robot of Div B driving into a ring around the ball, so islands hold many bodies
// and contacts, and the order the broadphase reports pairs in shapes the solver's rows.
std::uint64_t Scrum(World& world, int count) {
  std::uint64_t digest = 0;
  for (int i = 0; i < count; ++i) {
    const std::int64_t step = world.clock().steps();
    const WorldSnapshot now = world.GroundTruth();
    if (step % 10 == 0) {
      for (const RobotState& r : now.robots) {
        const Vec3 to_ball = now.ball.pose.position - r.pose.position;
        const double yaw = r.pose.Yaw();
        const double c = std::cos(yaw), s = std::sin(yaw);
        CommandEvent e;
        e.robot = r.id;
        e.move = LocalVelocityCommand{c * to_ball.x() + s * to_ball.y(), -s * to_ball.x() + c * to_ball.y(),
                                      std::sin(1e-3 * static_cast<double>(step) + r.id.id)};
        e.dribbler_speed = 100.0;
        world.events().Post(e);
      }
    }
    world.Step();
    digest = digest * 1099511628211ULL ^ world.StateHash();
  }
  return digest;
}

TEST_P(Broadphase, RestoredScrumIsBitIdentical) {
  Worlds s;
  WorldModel model = s.Load("div-b", GetParam());
  for (std::size_t i = 0; i < model.robots.size(); ++i) {  // a ring of 12 robots, 0.45 m round the ball
    const double a = 2 * M_PI * static_cast<double>(i) / static_cast<double>(model.robots.size());
    model.robots[i].x = 0.45 * std::cos(a);
    model.robots[i].y = 0.45 * std::sin(a);
    model.robots[i].yaw = a + M_PI;
  }
  std::string bytes;
  std::uint64_t original = 0;
  {
    World world(model, s.registry, s.log, false);
    Scrum(world, 1500);
    bytes = EncodeSnapshot(world.Save());
    original = Scrum(world, 1500);
  }
  World world(model, s.registry, s.log, false);
  world.Restore(DecodeSnapshot(bytes, "memory"));
  EXPECT_EQ(Scrum(world, 1500), original);
}

INSTANTIATE_TEST_SUITE_P(Snapshot, Broadphase, ::testing::Values("sap", "hash", "scene_graph", "field"));

TEST(Snapshot, ASecondRestoreOfTheSameSnapshotGoesTheSameWay) {
  Worlds s;
  const WorldModel model = s.Load("div-b");
  World world(model, s.registry, s.log, false);
  StepAndDigest(world, 800);
  const SavedState saved = world.Save();
  world.Restore(saved);
  const std::uint64_t first = StepAndDigest(world, 600);
  world.Restore(saved);  // the same world object, restored again
  EXPECT_EQ(StepAndDigest(world, 600), first);
}

// ---------------------------------------------------------------------------------------------
// Refusals

fs::path TempDir() {
  const fs::path dir = fs::temp_directory_path() / ("ubersim_snapshot_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const SnapshotError& e) {
    return e.what();
  }
  return "(no SnapshotError)";
}

TEST(Snapshot, RefusesASnapshotOfAnotherWorldNamingBoth) {
  Worlds s;
  World div_b(s.Load("div-b"), s.registry, s.log, false);
  StepAndDigest(div_b, 100);
  const SavedState saved = div_b.Save();
  World ssl(s.Load("ssl-2003"), s.registry, s.log, false);
  StepAndDigest(ssl, 50);
  const std::uint64_t before = ssl.StateHash();
  const std::string error = ErrorOf([&] { ssl.Restore(saved); });
  EXPECT_NE(error.find("the snapshot is of world 'div-b' (" UBERSIM_SOURCE_DIR "/models/worlds/div-b.yaml), not of world "
                       "'ssl-2003' (" UBERSIM_SOURCE_DIR "/models/worlds/ssl-2003.yaml)"),
            std::string::npos)
      << error;
  EXPECT_EQ(ssl.StateHash(), before);  // refused before anything changed
  EXPECT_EQ(ssl.clock().steps(), 50);
}

TEST(Snapshot, RefusesASnapshotOfTheSameNameWithOtherRobotsOrPhysics) {
  Worlds s;
  const WorldModel model = s.Load("div-b");
  World world(model, s.registry, s.log, false);
  const SavedState saved = world.Save();

  // A world file with one robot fewer: the snapshot's twelfth robot came on while it ran, and
  // comes back from its team's model.
  WorldModel fewer = model;
  fewer.robots.pop_back();
  World small(fewer, s.registry, s.log, false);
  small.Restore(saved);
  EXPECT_EQ(small.robot_count(), 12u);
  EXPECT_EQ(small.StateHash(), world.StateHash());
  // A robot built from a file this world does not name cannot come back.
  SavedState stranger = saved;
  stranger.robots.back().model_file = "/elsewhere/robot.yaml";
  EXPECT_NE(ErrorOf([&] { small.Restore(stranger); }).find("was built from /elsewhere/robot.yaml"), std::string::npos)
      << ErrorOf([&] { small.Restore(stranger); });

  WorldModel coarse = model;
  coarse.physics.solver_iterations = model.physics.solver_iterations + 5;
  World other(coarse, s.registry, s.log, false);
  EXPECT_NE(ErrorOf([&] { other.Restore(saved); }).find("other bodies, geometries, masses or physics settings"),
            std::string::npos);

  WorldModel slower = model;
  slower.physics.step = 0.002;  // not the shipped world's (1 ms precise, 5 ms fast)
  World stepping(slower, s.registry, s.log, false);
  const std::string step_ns = std::to_string(std::llround(model.physics.step * 1e9));
  EXPECT_NE(ErrorOf([&] { stepping.Restore(saved); }).find("physics step is " + step_ns + " ns, this world's 2000000 ns"),
            std::string::npos);
}

TEST(Snapshot, AFileRoundTripsAndIsWrittenWhole) {
  Worlds s;
  World world(s.Load("div-b"), s.registry, s.log, false);
  StepAndDigest(world, 300);
  const fs::path file = TempDir() / "div-b.snapshot";
  const SavedState saved = world.Save();
  WriteSnapshotFile(file, saved);
  EXPECT_FALSE(fs::exists(file.string() + ".tmp" + std::to_string(::getpid())));
  const SavedState back = ReadSnapshotFile(file);
  EXPECT_EQ(back.world_name, "div-b");
  EXPECT_EQ(back.world_file, UBERSIM_SOURCE_DIR "/models/worlds/div-b.yaml");
  EXPECT_EQ(back.step, 300);
  EXPECT_EQ(back.time_ns, 300 * std::llround(world.model().physics.step * 1e9));
  EXPECT_EQ(back.model_files.size(), 4u);  // world, field, ball, robot model
  EXPECT_EQ(EncodeSnapshot(back), EncodeSnapshot(saved));  // nothing lost on the way
  fs::remove_all(file.parent_path());
}

TEST(Snapshot, TruncatedCorruptAndForeignFilesAreRefusedWithTheFileAndTheReason) {
  Worlds s;
  World world(s.Load("ssl-2003"), s.registry, s.log, false);
  StepAndDigest(world, 200);
  const std::string bytes = EncodeSnapshot(world.Save());
  const fs::path dir = TempDir();
  const fs::path file = dir / "bad.snapshot";
  auto refusal = [&](const std::string& content) {
    std::ofstream(file, std::ios::binary | std::ios::trunc) << content;
    return ErrorOf([&] { ReadSnapshotFile(file); });
  };
  auto expect = [&](const std::string& error, const std::string& reason) {
    EXPECT_EQ(error.rfind(file.string() + ": ", 0), 0u) << error;
    EXPECT_NE(error.find(reason), std::string::npos) << error;
  };
  expect(refusal(""), "empty file, not an ÜberSim snapshot");
  expect(refusal("kind: world\nname: div-b\n"), "not an ÜberSim snapshot");
  // Cut anywhere: refused, never half read, never a crash.
  for (std::size_t keep = 1; keep < bytes.size(); keep += 1 + keep / 3) {
    const std::string error = refusal(bytes.substr(0, keep));
    EXPECT_EQ(error.rfind(file.string() + ": ", 0), 0u) << keep << ": " << error;
    EXPECT_TRUE(error.find("truncated") != std::string::npos || error.find("corrupt") != std::string::npos ||
                error.find("not an ÜberSim snapshot") != std::string::npos)
        << keep << ": " << error;
  }
  expect(refusal(bytes.substr(0, bytes.size() / 2)), "truncated");
  // One bit flipped anywhere in the state: the checksum catches it.
  for (std::size_t at = 40; at < bytes.size() - 20; at += 997) {
    std::string flipped = bytes;
    flipped[at] = static_cast<char>(flipped[at] ^ 0x10);
    const std::string error = refusal(flipped);
    EXPECT_EQ(error.rfind(file.string() + ": ", 0), 0u) << at << ": " << error;
  }
  std::string flipped = bytes;
  flipped[bytes.size() / 2] = static_cast<char>(flipped[bytes.size() / 2] ^ 0x01);
  expect(refusal(flipped), "corrupt: its checksum does not match its contents");
  EXPECT_NE(ErrorOf([&] { ReadSnapshotFile(dir / "absent.snapshot"); }).find("absent.snapshot: no such file"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { ReadSnapshotFile(dir); }).find("not a regular file"), std::string::npos);
  fs::remove_all(dir);
}

TEST(Snapshot, APartThatCannotReadItsSavedStateIsNamedAndTheWorldStaysFresh) {
  Worlds s;
  const WorldModel model = s.Load("div-b");
  World world(model, s.registry, s.log, false);
  StepAndDigest(world, 100);
  SavedState saved = world.Save();
  saved.robots[2].parts[2].state.resize(5);  // blue 2's kicker: a truncated state
  World other(model, s.registry, s.log, false);
  const std::string error = ErrorOf([&] { other.Restore(saved); });
  EXPECT_NE(error.find("blue/2 kicker 'solenoid'"), std::string::npos) << error;
  EXPECT_NE(error.find("refused its saved state: solenoid kicker: saved state is unreadable: truncated"), std::string::npos)
      << error;
  EXPECT_EQ(other.clock().steps(), 0);
}

TEST(StateIo, ReadsWhatItWroteAndRefusesOtherLayoutsAndShortStates) {
  const std::string state = StateWriter(3)
                                .Double(-0.0)
                                .Double(std::nextafter(1.0, 2.0))
                                .Bool(true)
                                .Int(-7)
                                .Move(WheelSpeedCommand{{1.5, -2.5, 3.5, 0.25}})
                                .Take();
  StateReader r(state, 3, "test");
  const double zero = r.Double();
  EXPECT_TRUE(std::signbit(zero));
  EXPECT_EQ(r.Double(), std::nextafter(1.0, 2.0));
  EXPECT_TRUE(r.Bool());
  EXPECT_EQ(r.Int(), -7);
  const MoveCommand m = r.Move();
  ASSERT_TRUE(std::holds_alternative<WheelSpeedCommand>(m));
  EXPECT_EQ(std::get<WheelSpeedCommand>(m).wheel_speeds, (std::vector<double>{1.5, -2.5, 3.5, 0.25}));
  r.Finish();
  EXPECT_THROW(StateReader(state, 4, "test"), PluginError);
  // The reader keeps a view: the cut and the lengthened state must outlive it.
  const std::string cut = state.substr(0, 20);
  StateReader short_reader(cut, 3, "test");
  short_reader.Double();
  EXPECT_THROW(short_reader.Double(), PluginError);
  const std::string lengthened = state + "x";
  StateReader long_reader(lengthened, 3, "test");
  EXPECT_THROW(
      {
        long_reader.Double();
        long_reader.Double();
        long_reader.Bool();
        long_reader.Int();
        long_reader.Move();
        long_reader.Finish();
      },
      PluginError);
}

}  // namespace
}  // namespace ubersim::kernel
