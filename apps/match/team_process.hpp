// SPDX-License-Identifier: Apache-2.0
// A team's software as `ubersim match` runs it: a shell command started in its own process group
// with the match's settings in its environment, watched without blocking, and stopped (SIGTERM to
// the group, then SIGKILL) so that no child of it outlives the match.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace ubersim::match {

/// One running team program.
class TeamProcess {
 public:
  /// Starts `/bin/sh -c command` with `environment` added to ours; its output goes to `output_file`
  /// (appended) or, when empty, to ours. Throws std::runtime_error naming the command and reason.
  TeamProcess(std::string name, const std::string& command,
              const std::vector<std::pair<std::string, std::string>>& environment, const std::string& output_file = "");
  /// Stops it if it still runs.
  ~TeamProcess();
  TeamProcess(const TeamProcess&) = delete;
  TeamProcess& operator=(const TeamProcess&) = delete;

  /// How it ended ("exit code 3", "killed by signal 9"), or nothing while it runs. Never blocks.
  std::optional<std::string> Ended();
  /// Ends it: SIGTERM to its process group, SIGKILL after `grace`. Returns how it ended.
  std::string Stop(std::chrono::milliseconds grace = std::chrono::milliseconds(2000));
  /// Its process id (also its process group's).
  pid_t pid() const { return pid_; }
  /// The name it was given ("yellow").
  const std::string& name() const { return name_; }

 private:
  std::string name_;
  pid_t pid_ = -1;
  std::optional<std::string> ended_;
};

}  // namespace ubersim::match
