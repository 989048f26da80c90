// SPDX-License-Identifier: Apache-2.0
// A drive whose constructor throws, as one that probes for hardware might.
#include <stdexcept>

#include <ubersim/ubersim.hpp>

namespace {
class ThrowingDrive final : public ubersim::Drive {
 public:
  ThrowingDrive() { throw std::runtime_error("no motor controller on /dev/ttyACM0"); }
  void Configure(ubersim::RobotContext&) override {}
  void SetCommand(const ubersim::MoveCommand&) override {}
  ubersim::DriveFeedback Feedback() const override { return {}; }
};
}  // namespace

UBERSIM_REGISTER_DRIVE(ThrowingDrive, "fake_throwing", "1.0", R"({"type": "object"})")
