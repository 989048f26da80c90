// SPDX-License-Identifier: Apache-2.0
// A transport without a network that throws on purpose: `fault: poll` or `fault: publish`, from
// the `after`-th call on (0: the first).
#include <stdexcept>
#include <string>

#include <ubersim/ubersim.hpp>

namespace {

class FaultyTransport final : public ubersim::Transport {
 public:
  void Start(ubersim::TransportContext& ctx) override {
    fault_ = ctx.Params().GetString("fault", "none");
    after_ = ctx.Params().GetInt("after", 0);
  }
  void Poll() override {
    if (fault_ == "poll" && polls_++ >= after_) throw std::runtime_error("socket closed under me");
  }
  void Publish(const ubersim::WorldSnapshot&) override {
    if (fault_ == "publish" && publishes_++ >= after_) throw std::runtime_error("encoder bug");
  }
  void Stop() override {}

 private:
  std::string fault_;
  std::int64_t after_ = 0;
  std::int64_t polls_ = 0, publishes_ = 0;
};

}  // namespace

UBERSIM_REGISTER_TRANSPORT(FaultyTransport, "faulty_transport", "1.0", R"({"type": "object"})")
