// SPDX-License-Identifier: Apache-2.0
// A correct kicker whose descriptor id differs from its file name (libubersim_fake_misnamed.so).
#include <ubersim/ubersim.hpp>

namespace {
class Kicker final : public ubersim::Kicker {
 public:
  void Configure(ubersim::RobotContext&) override {}
  bool Kick(const ubersim::KickCommand&) override { return false; }
  bool Ready() const override { return true; }
};
}  // namespace

UBERSIM_REGISTER_KICKER(Kicker, "fake_renamed", "1.0", R"({"type": "object"})")
