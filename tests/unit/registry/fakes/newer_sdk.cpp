// SPDX-License-Identifier: Apache-2.0
// A plugin built against a newer SDK minor than this kernel provides (same ABI word).
#include <ubersim/ubersim.hpp>

namespace {
class NewerDrive final : public ubersim::Drive {
 public:
  void Configure(ubersim::RobotContext&) override {}
  void SetCommand(const ubersim::MoveCommand&) override {}
  ubersim::DriveFeedback Feedback() const override { return {}; }
};
void* Create() { return static_cast<ubersim::Drive*>(new NewerDrive()); }
void Destroy(void* p) { delete static_cast<ubersim::Drive*>(p); }
const ubersim::PluginDescriptor kDescriptor{
    ubersim::kPluginAbiWord, sizeof(ubersim::PluginDescriptor), ubersim::PluginKind::kDrive,
    ubersim::kSdkVersionMajor, ubersim::kSdkVersionMinor + 1, "fake_newer_sdk", "1.0",
    ubersim::kBuildTag, "{}", &Create, &Destroy};
}  // namespace

namespace fake {
const ubersim::PluginDescriptor* Descriptor() { return &kDescriptor; }
const std::uint32_t kAbiWord = ubersim::kPluginAbiWord;
}  // namespace fake
BOOST_DLL_ALIAS(fake::Descriptor, ubersim_plugin_v1)
BOOST_DLL_ALIAS(fake::kAbiWord, ubersim_abi_word)
