// SPDX-License-Identifier: Apache-2.0
#include "team_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace ubersim::match {
namespace {

std::string HowEnded(int status) {
  if (WIFEXITED(status)) return "exit code " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
  return "ended (status " + std::to_string(status) + ")";
}

}  // namespace

TeamProcess::TeamProcess(std::string name, const std::string& command,
                         const std::vector<std::pair<std::string, std::string>>& environment, const std::string& output_file)
    : name_(std::move(name)) {
  std::vector<std::string> env_text;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry(*e);
    bool replaced = false;
    for (const auto& [key, value] : environment) replaced = replaced || entry.rfind(key + "=", 0) == 0;
    if (!replaced) env_text.push_back(entry);
  }
  for (const auto& [key, value] : environment) env_text.push_back(key + "=" + value);
  std::vector<char*> envp;
  for (auto& e : env_text) envp.push_back(e.data());
  envp.push_back(nullptr);
  std::string sh = "/bin/sh", dash_c = "-c", cmd = command;
  char* argv[] = {sh.data(), dash_c.data(), cmd.data(), nullptr};

  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  // Its own process group: Stop signals the shell and everything it started.
  posix_spawnattr_setpgroup(&attr, 0);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (!output_file.empty()) {
    posix_spawn_file_actions_addopen(&actions, 1, output_file.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
  }
  const int error = posix_spawn(&pid_, "/bin/sh", &actions, &attr, argv, envp.data());
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  if (error != 0) throw std::runtime_error(name_ + " team: cannot start '" + command + "': " + std::strerror(error));
}

TeamProcess::~TeamProcess() {
  if (!ended_) Stop(std::chrono::milliseconds(500));
}

std::optional<std::string> TeamProcess::Ended() {
  if (ended_) return ended_;
  int status = 0;
  const pid_t r = ::waitpid(pid_, &status, WNOHANG);
  if (r == pid_) {
    ended_ = HowEnded(status);
    ::kill(-pid_, SIGTERM);  // what it left running goes too
  } else if (r < 0 && errno == ECHILD) {
    ended_ = "ended (not our child)";
  }
  return ended_;
}

std::string TeamProcess::Stop(std::chrono::milliseconds grace) {
  if (Ended()) return *ended_;
  ::kill(-pid_, SIGTERM);
  const auto until = std::chrono::steady_clock::now() + grace;
  while (std::chrono::steady_clock::now() < until) {
    if (Ended()) return *ended_;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ::kill(-pid_, SIGKILL);
  int status = 0;
  ::waitpid(pid_, &status, 0);
  ended_ = HowEnded(status);
  return *ended_;
}

}  // namespace ubersim::match
