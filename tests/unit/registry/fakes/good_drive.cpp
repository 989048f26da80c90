// SPDX-License-Identifier: Apache-2.0
// A correct drive: pushes nothing, reports its command back as feedback.
#include <variant>

#include <ubersim/ubersim.hpp>

namespace {
class GoodDrive final : public ubersim::Drive {
 public:
  void Configure(ubersim::RobotContext&) override {}
  void SetCommand(const ubersim::MoveCommand& c) override {
    if (const auto* l = std::get_if<ubersim::LocalVelocityCommand>(&c)) forward_ = l->forward;
  }
  ubersim::DriveFeedback Feedback() const override {
    ubersim::DriveFeedback f;
    f.local_velocity.linear.x() = forward_;
    return f;
  }

 private:
  double forward_ = 0;
};
}  // namespace

UBERSIM_REGISTER_DRIVE(GoodDrive, "fake_good", "2.3.4", R"({"type": "object"})")
