// SPDX-License-Identifier: Apache-2.0
// `ubersim batch`'s runner: deterministic per world whatever the number of workers, and a world
// that throws or crashes is reported without taking the others down. No timing asserted.
#include <cstdlib>
#include <sstream>

#include <gtest/gtest.h>

#include "batch.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"

namespace ubersim::kernel::batch {
namespace {

struct BatchRunner : ::testing::Test {
  std::ostringstream text;
  StreamLog log{text, LogLevel::kError};
  PluginRegistry registry{{UBERSIM_PLUGIN_BUILD_DIR}};
  ModelLoader loader{ModelLoader::DefaultSchemaDir(),
                     [this](PluginKind k, const std::string& id) { return registry.Find(k, id).schema_json; }};
  WorldModel model = loader.LoadWorld(UBERSIM_SOURCE_DIR "/models/worlds/ssl-2003.yaml");

  WorldFactory Factory() {
    return [this](const BatchJob& job) {
      WorldModel m = model;
      m.transports.clear();
      m.physics.step = 0.002;  // shorter tests; the same for every worker count
      m.seed = job.seed;
      return std::make_unique<World>(m, registry, log, false);
    };
  }
  BatchOptions Options(int jobs, int workers) {
    BatchOptions o;
    for (int i = 0; i < jobs; ++i) o.jobs.push_back(BatchJob{"ssl-2003.yaml", static_cast<std::uint64_t>(10 + i)});
    o.workers = workers;
    o.sim_seconds = 0.3;
    return o;
  }
};

TEST_F(BatchRunner, TheSameSeedGivesTheSameStateWhateverTheNumberOfWorkers) {
  double last_fraction = 0;
  const BatchSummary one = RunBatch(Options(4, 1), Factory(), nullptr);
  const BatchSummary two = RunBatch(Options(4, 2), Factory(), [&](std::size_t, std::size_t, double f) {
    EXPECT_GE(f, last_fraction - 1e-12) << "progress never goes back";
    last_fraction = f;
  });
  EXPECT_DOUBLE_EQ(last_fraction, 1.0);
  ASSERT_EQ(one.jobs.size(), 4u);
  ASSERT_EQ(two.jobs.size(), 4u);
  EXPECT_EQ(two.workers, 2);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(one.jobs[i].error, "");
    EXPECT_EQ(two.jobs[i].error, "");
    EXPECT_EQ(one.jobs[i].world, "ssl-2003");
    EXPECT_EQ(one.jobs[i].steps, 150);
    EXPECT_NEAR(one.jobs[i].sim_seconds, 0.3, 1e-9);
    EXPECT_EQ(one.jobs[i].state_hash, two.jobs[i].state_hash) << "job " << i;
  }
  EXPECT_NE(one.jobs[0].state_hash, one.jobs[1].state_hash) << "other seeds play otherwise";
  // And the same as running the job in this process.
  const BatchJobResult here = RunJob(BatchJob{"ssl-2003.yaml", 12}, 2, 0.3, Factory(), nullptr);
  EXPECT_EQ(here.state_hash, one.jobs[2].state_hash);
  EXPECT_NEAR(two.sim_seconds, 1.2, 1e-9);
}

TEST_F(BatchRunner, AWorldThatFailsIsReportedAndTheOthersFinish) {
  const WorldFactory good = Factory();
  const BatchSummary s = RunBatch(Options(3, 2), [&](const BatchJob& job) -> std::unique_ptr<World> {
    if (job.seed == 11) throw std::runtime_error("robot blue 3: no such plugin 'omni2'");
    return good(job);
  }, nullptr);
  EXPECT_EQ(s.Failed(), 1);
  EXPECT_EQ(s.jobs[1].error, "robot blue 3: no such plugin 'omni2'");
  EXPECT_EQ(s.jobs[0].error, "");
  EXPECT_EQ(s.jobs[2].error, "");
  EXPECT_NEAR(s.sim_seconds, 0.6, 1e-9);
}

TEST_F(BatchRunner, AWorkerThatCrashesIsReportedWithItsSignal) {
  const WorldFactory good = Factory();
  // Worker 1 gets jobs 1 and 3; job 1 aborts the process, so job 3 never runs.
  const BatchSummary s = RunBatch(Options(4, 2), [&](const BatchJob& job) -> std::unique_ptr<World> {
    if (job.seed == 11) std::abort();
    return good(job);
  }, nullptr);
  EXPECT_EQ(s.Failed(), 2);
  EXPECT_NE(s.jobs[1].error.find("killed by signal 6"), std::string::npos) << s.jobs[1].error;
  EXPECT_NE(s.jobs[3].error.find("killed by signal 6"), std::string::npos) << s.jobs[3].error;
  EXPECT_EQ(s.jobs[0].error, "");
  EXPECT_EQ(s.jobs[2].error, "");
}

}  // namespace
}  // namespace ubersim::kernel::batch
