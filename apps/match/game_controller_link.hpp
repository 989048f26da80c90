// SPDX-License-Identifier: Apache-2.0
// The TCP connection to a game controller in CI mode (ssl-match-protocols.md §1.2–1.4): each
// CiInput out, varint-delimited, and every CiOutput back. Lock step: Exchange blocks for the first
// output of an input, then takes what else has arrived, so the game controller's clock is the
// simulation's and a run faster than real time stays in step.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "ssl_gc_ci.pb.h"

namespace ubersim::match {

/// One CI connection to ssl-game-controller (or anything speaking its CI protocol).
class GameControllerLink {
 public:
  /// Connects to "HOST:PORT"; throws std::runtime_error naming the address and the reason.
  explicit GameControllerLink(const std::string& address,
                              std::chrono::milliseconds timeout = std::chrono::milliseconds(5000));
  ~GameControllerLink();
  GameControllerLink(const GameControllerLink&) = delete;
  GameControllerLink& operator=(const GameControllerLink&) = delete;

  /// Sends `input` and returns the Referee messages of every CiOutput received: at least one, or
  /// std::runtime_error when none comes within the timeout or the connection breaks.
  std::vector<Referee> Exchange(const CiInput& input);
  /// "game controller 127.0.0.1:10009 (CI mode)".
  std::string Describe() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ubersim::match
