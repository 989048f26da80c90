// SPDX-License-Identifier: Apache-2.0
// The plugin registry against real shared libraries: a good plugin loads and runs; a missing
// file, a file that is no library, a library that is no plugin, another plugin ABI, a newer SDK,
// a misnamed file and a throwing constructor are each refused with the file and the reason, and
// the registry (and a world built with it) carries on.
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "../../common/test_world.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/plugin_registry.hpp"
#include "ubersim/kernel/world.hpp"

namespace ubersim::kernel {
namespace {

namespace fs = std::filesystem;

fs::path Fake(const std::string& name) {
  return fs::path(UBERSIM_FAKE_PLUGIN_DIR) / ("libubersim_" + name + ".so");
}

// Runs `f`, expects a PluginLoadError, and returns it.
template <typename F>
PluginLoadError Refusal(F&& f) {
  try {
    f();
  } catch (const PluginLoadError& e) {
    return e;
  }
  ADD_FAILURE() << "no PluginLoadError was thrown";
  return PluginLoadError("", "");
}

TEST(PluginRegistry, AGoodPluginLoadsAndRuns) {
  PluginRegistry registry({UBERSIM_FAKE_PLUGIN_DIR});
  const PluginInfo& info = registry.LoadFile(Fake("fake_good"));
  EXPECT_EQ(info.id, "fake_good");
  EXPECT_EQ(info.kind, PluginKind::kDrive);
  EXPECT_EQ(info.version, "2.3.4");
  EXPECT_EQ(info.sdk_version, std::to_string(kSdkVersionMajor) + "." + std::to_string(kSdkVersionMinor));
  EXPECT_EQ(info.file, fs::canonical(Fake("fake_good")));
  auto drive = registry.CreateDrive("fake_good");
  drive->SetCommand(LocalVelocityCommand{1.25, 0, 0});
  EXPECT_EQ(drive->Feedback().local_velocity.linear.x(), 1.25);  // plugin code ran
}

TEST(PluginRegistry, AMissingFileIsRefusedByName) {
  PluginRegistry registry({});
  const PluginLoadError e = Refusal([&] { registry.LoadFile(Fake("fake_not_there")); });
  EXPECT_EQ(e.where(), Fake("fake_not_there").string());
  EXPECT_EQ(e.reason(), "no such file");
}

TEST(PluginRegistry, AFileThatIsNoLibraryIsRefusedWithTheLoadersReason) {
  PluginRegistry registry({});
  const PluginLoadError e = Refusal([&] { registry.LoadFile(Fake("fake_garbage")); });
  EXPECT_EQ(e.where(), Fake("fake_garbage").string());
  EXPECT_EQ(e.reason().rfind("cannot be loaded: ", 0), 0u) << e.reason();
  EXPECT_NE(e.reason().find("libubersim_fake_garbage.so"), std::string::npos) << e.reason();
}

TEST(PluginRegistry, ALibraryThatIsNoPluginIsRefused) {
  PluginRegistry registry({});
  const PluginLoadError e = Refusal([&] { registry.LoadFile(Fake("fake_plain")); });
  EXPECT_EQ(e.where(), Fake("fake_plain").string());
  EXPECT_EQ(e.reason(), "not an ÜberSim plugin (no ubersim_abi_word symbol)");
}

TEST(PluginRegistry, ANewerSdkIsRefused) {
  PluginRegistry registry({});
  const PluginLoadError e = Refusal([&] { registry.LoadFile(Fake("fake_newer_sdk")); });
  EXPECT_EQ(e.where(), Fake("fake_newer_sdk").string());
  const std::string major = std::to_string(kSdkVersionMajor);
  EXPECT_EQ(e.reason(), "built against SDK " + major + "." + std::to_string(kSdkVersionMinor + 1) +
                            ", this kernel provides SDK " + major + "." +
                            std::to_string(kSdkVersionMinor));
}

TEST(PluginRegistry, AnotherPluginAbiIsRefusedBeforeAnyOfItsCodeRuns) {
  PluginRegistry registry({});
  // The fake's descriptor function aborts the process: reaching the assertion proves it never ran.
  const PluginLoadError e = Refusal([&] { registry.LoadFile(Fake("fake_other_abi")); });
  EXPECT_EQ(e.where(), Fake("fake_other_abi").string());
  EXPECT_NE(e.reason().find("built for plugin ABI " + std::to_string(kPluginAbiVersion + 1)),
            std::string::npos) << e.reason();
  EXPECT_NE(e.reason().find("this kernel has plugin ABI " + std::to_string(kPluginAbiVersion)),
            std::string::npos) << e.reason();
}

TEST(PluginRegistry, AThrowingConstructorIsRefusedWithItsMessage) {
  PluginRegistry registry({UBERSIM_FAKE_PLUGIN_DIR});
  const PluginLoadError e = Refusal([&] { registry.CreateDrive("fake_throwing"); });
  EXPECT_EQ(e.where(), fs::canonical(Fake("fake_throwing")).string());
  EXPECT_EQ(e.reason(), "plugin 'fake_throwing': constructor threw: no motor controller on /dev/ttyACM0");
}

TEST(PluginRegistry, AFileWhoseDescriptorNamesAnotherIdIsRefused) {
  PluginRegistry registry({UBERSIM_FAKE_PLUGIN_DIR});
  const PluginLoadError e = Refusal([&] { registry.Find(PluginKind::kKicker, "fake_misnamed"); });
  EXPECT_FALSE(e.not_found());
  EXPECT_EQ(e.reason().rfind("refused: ", 0), 0u) << e.reason();
  EXPECT_NE(e.reason().find("libubersim_fake_misnamed.so: file is named for 'fake_misnamed' but its descriptor "
                            "says 'fake_renamed'"),
            std::string::npos)
      << e.reason();
}

// A refused library earlier in the search path (a stale build, another ABI, not a library at all)
// does not hide a good one later: the good one is used and the stale one is said to be skipped;
// with no good one, the error says "refused" and why, never "not found".
TEST(PluginRegistry, ARefusedLibraryEarlierInThePathDoesNotHideAGoodOneLater) {
  const fs::path stale = fs::temp_directory_path() / ("ubersim_stale_plugins_" + std::to_string(::getpid()));
  fs::create_directories(stale);
  fs::copy_file(Fake("fake_other_abi"), stale / "libubersim_fake_good.so", fs::copy_options::overwrite_existing);
  {
    PluginRegistry registry({stale, UBERSIM_FAKE_PLUGIN_DIR});
    const PluginInfo& info = registry.Find(PluginKind::kDrive, "fake_good");
    EXPECT_EQ(info.file, fs::canonical(Fake("fake_good")));
    ASSERT_EQ(registry.Skipped().size(), 1u);
    EXPECT_NE(registry.Skipped()[0].find((stale / "libubersim_fake_good.so").string() + ": built for"), std::string::npos)
        << registry.Skipped()[0];
    EXPECT_NE(registry.Skipped()[0].find("skipped: using " + fs::canonical(Fake("fake_good")).string()),
              std::string::npos)
        << registry.Skipped()[0];
    // A scan lists the file a lookup uses, and the stale one among the refused.
    const PluginRegistry::ScanResult scan = registry.Scan();
    bool listed = false;
    for (const PluginInfo& p : scan.plugins) listed = listed || (p.id == "fake_good" && p.file == info.file);
    EXPECT_TRUE(listed);
  }
  {
    PluginRegistry registry({stale});
    const PluginLoadError e = Refusal([&] { registry.Find(PluginKind::kDrive, "fake_good"); });
    EXPECT_FALSE(e.not_found());
    EXPECT_EQ(e.reason().rfind("refused: " + (stale / "libubersim_fake_good.so").string() + ": built for", 0), 0u)
        << e.reason();
  }
  fs::remove_all(stale);
}

TEST(PluginRegistry, AskingForTheWrongKindOrAnUnknownIdSaysWhatWasFound) {
  PluginRegistry registry({UBERSIM_FAKE_PLUGIN_DIR});
  const PluginLoadError kind = Refusal([&] { registry.CreateKicker("fake_good"); });
  EXPECT_EQ(kind.reason(), "'fake_good' is a drive plugin, not a kicker");
  const PluginLoadError unknown = Refusal([&] { registry.Find(PluginKind::kDrive, "warp_drive"); });
  EXPECT_EQ(unknown.where(), "plugin 'warp_drive' (drive)");
  EXPECT_TRUE(unknown.not_found());
  EXPECT_NE(unknown.reason().find(fs::canonical(UBERSIM_FAKE_PLUGIN_DIR).string() + " (found: "),
            std::string::npos) << unknown.reason();
  EXPECT_NE(unknown.reason().find("fake_good"), std::string::npos) << unknown.reason();
}

TEST(PluginRegistry, ADuplicateIdIsRefusedNamingTheFirstFile) {
  PluginRegistry registry({});
  registry.LoadFile(Fake("fake_good"));
  const PluginDescriptor* good = nullptr;
  {
    // A second, in-process registration under the same id.
    static void* (*create)() = [] { return static_cast<void*>(nullptr); };
    static void (*destroy)(void*) = [](void*) {};
    static const PluginDescriptor d{kPluginAbiWord, sizeof(PluginDescriptor), PluginKind::kDrive,
                                    kSdkVersionMajor, kSdkVersionMinor, "fake_good", "9",
                                    kBuildTag, "{}", create, destroy};
    good = &d;
  }
  const PluginLoadError e = Refusal([&] { registry.Add(*good); });
  EXPECT_EQ(e.reason(), "duplicate plugin id 'fake_good': already loaded from " +
                            fs::canonical(Fake("fake_good")).string());
}

TEST(PluginRegistry, AScanListsGoodPluginsAndEveryRefusalThenCarriesOn) {
  PluginRegistry registry({UBERSIM_FAKE_PLUGIN_DIR});
  const PluginRegistry::ScanResult scan = registry.Scan();
  std::vector<std::string> ids;
  for (const PluginInfo& p : scan.plugins) ids.push_back(p.id);
  // Loading succeeds for these two; the throwing one fails only when an instance is made. The
  // misnamed file loads, but no lookup by name would use it: a problem, not a plugin.
  EXPECT_EQ(ids, (std::vector<std::string>{"fake_good", "fake_throwing"}));
  ASSERT_EQ(scan.problems.size(), 5u);
  for (const char* bad : {"fake_garbage", "fake_misnamed", "fake_newer_sdk", "fake_other_abi", "fake_plain"}) {
    bool named = false;
    for (const std::string& p : scan.problems) {
      named = named || p.rfind(fs::canonical(UBERSIM_FAKE_PLUGIN_DIR).string() + "/libubersim_" + bad + ".so: ", 0) == 0;
    }
    EXPECT_TRUE(named) << bad << " is not among the problems";
  }
  EXPECT_THROW(registry.CreateDrive("fake_throwing"), PluginLoadError);
  auto drive = registry.CreateDrive("fake_good");  // the registry still works
  ASSERT_NE(drive, nullptr);
}

TEST(PluginRegistry, AnInstanceKeepsItsLibraryAfterTheRegistryIsGone) {
  std::shared_ptr<Drive> drive;
  {
    PluginRegistry registry({UBERSIM_FAKE_PLUGIN_DIR});
    drive = registry.CreateDrive("fake_good");
  }
  drive->SetCommand(LocalVelocityCommand{0.5, 0, 0});
  EXPECT_EQ(drive->Feedback().local_velocity.linear.x(), 0.5);
  drive.reset();  // destroy runs in the still-loaded library
}

WorldModel WorldWithDrive(const std::string& plugin) {
  WorldModel w = testing::BallWorld();
  auto robot = std::make_shared<RobotModel>();
  robot->file = "<code>";
  robot->name = "fake";
  robot->body = RobotBodyInfo{2.0, 0.09, 0.15, 0.07, 0.0};
  robot->surface.name = "robot";
  robot->drive = ComponentModel{plugin, ParamView::FromJson("{}")};
  w.robots.push_back(RobotPlacement{{Team::kYellow, 1}, robot, 1.0, 0.0, 0.0, true});
  return w;
}

TEST(PluginRegistry, AWorldWithAThrowingPluginIsRefusedAndAnotherWorldRunsAfterIt) {
  std::ostringstream text;
  StreamLog log(text, LogLevel::kWarning);
  PluginRegistry registry({UBERSIM_FAKE_PLUGIN_DIR});
  const PluginLoadError e =
      Refusal([&] { World bad(WorldWithDrive("fake_throwing"), registry, log, false); });
  EXPECT_EQ(e.where(), fs::canonical(Fake("fake_throwing")).string());
  EXPECT_NE(e.reason().find("no motor controller"), std::string::npos);

  World good(WorldWithDrive("fake_good"), registry, log, false);
  for (int i = 0; i < 100; ++i) good.Step();
  EXPECT_EQ(good.clock().steps(), 100);
  EXPECT_EQ(good.GroundTruth().robots.size(), 1u);
}

}  // namespace
}  // namespace ubersim::kernel
