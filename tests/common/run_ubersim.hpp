// SPDX-License-Identifier: Apache-2.0
// Runs the built `ubersim` as a user does: a separate process, its output and how it ended.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace ubersim::testing {

/// How a `ubersim` process ended.
struct CliResult {
  int exit_code = -1;   ///< its exit code; -1: killed by a signal
  int signal = 0;       ///< the signal that killed it, 0 if none
  std::string output;   ///< stdout and stderr together
};

/// Runs `ubersim ARGS` from the build tree, with `env` (e.g. "FOO=1") before it on the command
/// line, and waits for it.
inline CliResult RunUbersim(const std::string& args, const std::string& env = "") {
  const std::string cmd = env + " " UBERSIM_BINARY_DIR "/bin/ubersim " + args + " 2>&1";
  CliResult r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), pipe)) r.output += buf.data();
  const int status = pclose(pipe);
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  // popen runs a shell, which reports a child killed by signal s as exit status 128 + s.
  if (WIFEXITED(status) && r.exit_code > 128) r.signal = r.exit_code - 128;
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  return r;
}

}  // namespace ubersim::testing
