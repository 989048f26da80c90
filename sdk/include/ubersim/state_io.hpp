// SPDX-License-Identifier: Apache-2.0
#pragma once
// Helpers for Component::SaveState / RestoreState: a component's state as a compact byte string
// that restores bit for bit (doubles are copied as their 64 bits, never printed), checked when
// read back. Header-only.

#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <variant>

#include "ubersim/error.hpp"
#include "ubersim/events.hpp"
#include "ubersim/servo.hpp"

namespace ubersim {
inline namespace v1 {

/// Builds a state string field by field; a StateReader reads the fields back in the same order.
/// Starts with `format`, the component's own number for its layout: bump it when the fields
/// change, and the reader refuses a state of another layout instead of misreading it.
class StateWriter {
 public:
  /// A writer for layout `format` of the component's state.
  explicit StateWriter(std::uint32_t format) { U64(format); }

  /// Appends a double, bit for bit.
  StateWriter& Double(double v) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    return U64(bits);
  }
  /// Appends a signed integer.
  StateWriter& Int(std::int64_t v) { return U64(static_cast<std::uint64_t>(v)); }
  /// Appends a flag.
  StateWriter& Bool(bool v) {
    out_.push_back(v ? '\1' : '\0');
    return *this;
  }
  /// Appends a move command (any of its three forms).
  StateWriter& Move(const MoveCommand& m) {
    U64(m.index());
    if (const auto* w = std::get_if<WheelSpeedCommand>(&m)) {
      U64(w->wheel_speeds.size());
      for (double s : w->wheel_speeds) Double(s);
    } else if (const auto* l = std::get_if<LocalVelocityCommand>(&m)) {
      Double(l->forward).Double(l->left).Double(l->angular);
    } else if (const auto* g = std::get_if<GlobalVelocityCommand>(&m)) {
      Double(g->x).Double(g->y).Double(g->angular);
    }
    return *this;
  }
  /// Appends a servo's setpoint.
  StateWriter& Setpoint(const PlanarVelocity& v) { return Double(v.linear.x()).Double(v.linear.y()).Double(v.angular); }
  /// Appends a command watchdog's memory (its timeout is configuration, not state).
  StateWriter& Watchdog(const CommandWatchdog& w) { return Double(w.LastFeed()).Bool(w.HasCommand()); }
  /// The state string (for SaveState to return).
  std::string Take() { return std::move(out_); }

 private:
  // Little-endian whatever the machine, so a snapshot file reads the same everywhere.
  StateWriter& U64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) out_.push_back(static_cast<char>((v >> (8 * i)) & 0xffU));
    return *this;
  }
  std::string out_;
};

/// Reads what a StateWriter wrote. Every read checks that the bytes are there, and the
/// constructor checks the layout number, so a truncated, foreign or older state throws
/// PluginError naming `who` instead of restoring garbage.
class StateReader {
 public:
  /// Reads `state`, written with layout `format`; `who` names the component in errors.
  StateReader(std::string_view state, std::uint32_t format, std::string who)
      : in_(state), who_(std::move(who)) {
    const std::uint64_t found = U64();
    if (found != format) {
      throw PluginError(who_ + ": saved state has layout " + std::to_string(found) + ", this version reads layout " +
                        std::to_string(format));
    }
  }

  /// Reads a double.
  double Double() {
    const std::uint64_t bits = U64();
    double v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }
  /// Reads a signed integer.
  std::int64_t Int() { return static_cast<std::int64_t>(U64()); }
  /// Reads a flag.
  bool Bool() {
    Need(1);
    const char c = in_[at_++];
    if (c != '\0' && c != '\1') Fail("a flag that is neither 0 nor 1");
    return c == '\1';
  }
  /// Reads a move command.
  MoveCommand Move() {
    switch (U64()) {
      case 0: {
        WheelSpeedCommand w;
        const std::uint64_t n = U64();
        if (n > (in_.size() - at_) / 8) Fail("more wheel speeds than bytes left");
        for (std::uint64_t i = 0; i < n; ++i) w.wheel_speeds.push_back(Double());
        return w;
      }
      case 1: {
        LocalVelocityCommand l;
        l.forward = Double();
        l.left = Double();
        l.angular = Double();
        return l;
      }
      case 2: {
        GlobalVelocityCommand g;
        g.x = Double();
        g.y = Double();
        g.angular = Double();
        return g;
      }
      default: Fail("an unknown kind of move command");
    }
  }
  /// Reads a servo's setpoint.
  PlanarVelocity Setpoint() {
    PlanarVelocity v;
    v.linear.x() = Double();
    v.linear.y() = Double();
    v.angular = Double();
    return v;
  }
  /// Reads a command watchdog's memory into `w`.
  void Watchdog(CommandWatchdog& w) {
    const double last = Double();
    w.Restore(last, Bool());
  }
  /// Checks that everything was read: leftover bytes mean the layouts differ.
  void Finish() const {
    if (at_ != in_.size()) Fail(std::to_string(in_.size() - at_) + " unread bytes at the end");
  }

 private:
  std::uint64_t U64() {
    Need(8);
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(static_cast<unsigned char>(in_[at_ + i])) << (8 * i);
    at_ += 8;
    return v;
  }
  void Need(std::size_t n) const {
    if (in_.size() - at_ < n) Fail("truncated (" + std::to_string(in_.size()) + " bytes)");
  }
  [[noreturn]] void Fail(const std::string& why) const { throw PluginError(who_ + ": saved state is unreadable: " + why); }

  std::string_view in_;
  std::size_t at_ = 0;
  std::string who_;
};

}  // namespace v1
}  // namespace ubersim
