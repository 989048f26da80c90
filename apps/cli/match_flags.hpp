// SPDX-License-Identifier: Apache-2.0
// The match options `ubersim run` and `ubersim match` share: the referee, tracked output and the
// log file they record (--referee, --tracker, --record, the match's length and teams).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include <boost/program_options.hpp>

#include "match_session.hpp"
#include "ssl_log.hpp"
#include "ubersim/kernel/model.hpp"

namespace ubersim::cli {

/// What the command line says about the match.
struct MatchFlags {
  std::string referee = "none";   ///< none, builtin or gc
  std::string game_controller = "localhost:10009";  ///< --game-controller HOST:PORT (CI mode)
  bool tracker = false;           ///< --tracker
  bool tracker_noise = false;     ///< --tracker-noise
  std::string record;             ///< --record FILE
  double half_duration = 300.0;   ///< s
  double half_time_break = 300.0; ///< s
  std::string first_kickoff = "yellow";
  std::string yellow_name = "Yellow", blue_name = "Blue";
  int yellow_keeper = 0, blue_keeper = 0;
  int referee_port = 10003;        ///< --referee-port
  int tracker_port = 10010;        ///< --tracker-port
  std::string placement = "auto";  ///< who places the ball: auto (teams, the simulator when they do not), simulator

  /// Adds the options to `desc`.
  void AddTo(boost::program_options::options_description& desc);
  /// The session's options for `model` (the division from its field), with the log writer made
  /// when --record is given (kept in `writer`). Throws UsageError for a bad value and
  /// std::runtime_error naming the file it cannot write.
  match::MatchOptions Options(const kernel::WorldModel& model, bool local_only, std::unique_ptr<sslog::LogWriter>& writer) const;
  /// Takes the world file's `match:` block for every option the command line left at its default.
  void FromWorld(const ParamView& block, const boost::program_options::variables_map& vm);
  /// True when any match option is on (a session is needed).
  bool Any() const { return referee != "none" || tracker || tracker_noise || !record.empty(); }
};

}  // namespace ubersim::cli
