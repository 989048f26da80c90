// SPDX-License-Identifier: Apache-2.0
#include "instructions.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <sstream>
#include <system_error>

extern char** environ;

namespace ubersim::kernel::bench {
namespace {

namespace fs = std::filesystem;

std::string Number(double x) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}

// The last `lines` lines of a file, for an error message.
std::string Tail(const fs::path& file, std::size_t lines = 15) {
  std::ifstream in(file);
  std::deque<std::string> last;
  std::string line;
  while (std::getline(in, line)) {
    last.push_back(line);
    if (last.size() > lines) last.pop_front();
  }
  std::string out;
  for (const std::string& l : last) out += "  | " + l + "\n";
  return out;
}

// A new private folder for one measurement's files.
fs::path MakeWorkFolder() {
  std::string pattern = (fs::temp_directory_path() / "ubersim-callgrind-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) {
    throw CallgrindError("--instructions: cannot make a temporary folder in " +
                         fs::temp_directory_path().string() + ": " + std::strerror(errno));
  }
  return pattern;
}

// Runs argv[0] with these arguments, its stdout and stderr into `log`, stdin from /dev/null,
// and waits for it: no shell, so no path is ever parsed as shell text. Returns the wait status.
int RunLogged(const std::vector<std::string>& argv, const fs::path& log) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = 0;
  const int spawned = ::posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    throw CallgrindError("--instructions: cannot start " + argv[0] + ": " + std::strerror(spawned));
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw CallgrindError(std::string("--instructions: waitpid: ") + std::strerror(errno));
  }
  return status;
}

std::string Describe(int status) {
  if (WIFEXITED(status)) return "exit code " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return "signal " + std::to_string(WTERMSIG(status));
  return "status " + std::to_string(status);
}

// One run under callgrind: its total instruction count.
std::uint64_t CountOnce(const CallgrindRun& run, double seconds, const fs::path& folder, const std::string& name) {
  const fs::path out = folder / (name + ".callgrind.out");
  const fs::path log = folder / (name + ".log");
  std::vector<std::string> argv = {run.valgrind.string(), "--tool=callgrind", "--callgrind-out-file=" + out.string(),
                                   run.program.string()};
  argv.insert(argv.end(), run.arguments.begin(), run.arguments.end());
  argv.push_back("--duration");
  argv.push_back(Number(seconds));
  const int status = RunLogged(argv, log);
  std::string command;
  for (const std::string& a : argv) command += (command.empty() ? "" : " ") + a;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw CallgrindError("--instructions: the callgrind run failed (" + Describe(status) + "): " + command +
                         "\nthe end of its output:\n" + Tail(log));
  }
  std::ifstream in(out);
  const auto total = CallgrindTotal(in);
  if (!total) {
    throw CallgrindError("--instructions: callgrind wrote no summary or totals line (" + command +
                         ")\nthe end of the run's output:\n" + Tail(log));
  }
  return *total;
}

}  // namespace

std::optional<std::uint64_t> CallgrindTotal(std::istream& in) {
  std::optional<std::uint64_t> summary, totals;
  std::string line;
  while (std::getline(in, line)) {
    for (const char* key : {"summary:", "totals:"}) {
      if (line.rfind(key, 0) != 0) continue;
      std::istringstream numbers(line.substr(std::strlen(key)));
      std::uint64_t n = 0;
      if (numbers >> n) (key[0] == 's' ? summary : totals) = n;
    }
  }
  return summary ? summary : totals;
}

std::optional<fs::path> FindValgrind() {
  // Debian's, the one the figures in docs/performance.md were counted with, when it is there.
  if (::access("/usr/bin/valgrind", X_OK) == 0) return fs::path("/usr/bin/valgrind");
  if (const char* path = std::getenv("PATH")) {
    std::istringstream dirs(path);
    std::string dir;
    while (std::getline(dirs, dir, ':')) {
      if (dir.empty()) continue;
      const fs::path candidate = fs::path(dir) / "valgrind";
      if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    }
  }
  return std::nullopt;
}

fs::path SelfExecutable() {
  std::error_code error;
  const fs::path self = fs::read_symlink("/proc/self/exe", error);
  if (error) throw CallgrindError("--instructions: cannot read /proc/self/exe: " + error.message());
  return self;
}

InstructionFigures MeasureInstructions(const CallgrindRun& run) {
  if (!(run.short_seconds > 0 && run.long_seconds > run.short_seconds && run.physics_step > 0)) {
    throw std::invalid_argument("--instructions: needs 0 < short duration < long duration");
  }
  const fs::path folder = MakeWorkFolder();
  InstructionFigures f;
  f.short_seconds = run.short_seconds;
  f.long_seconds = run.long_seconds;
  // The bench steps llround(duration / step) times.
  f.short_steps = std::llround(run.short_seconds / run.physics_step);
  f.long_steps = std::llround(run.long_seconds / run.physics_step);
  try {
    f.short_total = CountOnce(run, run.short_seconds, folder, "short");
    f.long_total = CountOnce(run, run.long_seconds, folder, "long");
  } catch (...) {
    std::error_code ignored;
    fs::remove_all(folder, ignored);  // the error carries the end of the output
    throw;
  }
  const double difference = static_cast<double>(f.long_total) - static_cast<double>(f.short_total);
  const auto steps = static_cast<double>(f.long_steps - f.short_steps);
  if (steps > 0) {
    f.per_step = difference / steps;
    f.per_sim_second = f.per_step / run.physics_step;
  }
  std::error_code ignored;
  fs::remove_all(folder, ignored);
  return f;
}

}  // namespace ubersim::kernel::bench
