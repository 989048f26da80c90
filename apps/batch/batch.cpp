// SPDX-License-Identifier: Apache-2.0
#include "batch.hpp"

#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <map>
#include <sstream>

#include "bench.hpp"

namespace ubersim::kernel::batch {
namespace {

using SteadyClock = std::chrono::steady_clock;

// Writes all of `text` to a pipe (the parent reads whole lines).
void WriteAll(int fd, const std::string& text) {
  const char* p = text.data();
  std::size_t left = text.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;  // the parent is gone: nothing left to tell
    p += n;
    left -= static_cast<std::size_t>(n);
  }
}

std::string OneLine(std::string s) {
  for (char& c : s) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return s;
}

// The worker: runs its share of the jobs and reports over `fd`. Never returns.
[[noreturn]] void WorkerMain(int fd, int worker, const BatchOptions& options, const WorldFactory& make_world) {
  for (std::size_t i = static_cast<std::size_t>(worker); i < options.jobs.size();
       i += static_cast<std::size_t>(options.workers)) {
    auto last = SteadyClock::now();
    const BatchJobResult r = RunJob(options.jobs[i], i, options.sim_seconds, make_world, [&](double f) {
      const auto now = SteadyClock::now();
      if (now - last < std::chrono::milliseconds(100)) return;
      last = now;
      char line[64];
      std::snprintf(line, sizeof line, "P %zu %.4f\n", i, f);
      WriteAll(fd, line);
    });
    char line[256];
    if (r.error.empty()) {
      std::snprintf(line, sizeof line, "R %zu %" PRId64 " %.17g %.17g %" PRIu64 " ", i, r.steps, r.sim_seconds,
                    r.wall_seconds, r.state_hash);
      WriteAll(fd, line + OneLine(r.world) + "\n");
    } else {
      WriteAll(fd, "E " + std::to_string(i) + " " + OneLine(r.error) + "\n");
    }
  }
  ::close(fd);
  // Leave without running the parent's exit handlers or destructors (they belong to it).
  ::_exit(0);
}

struct Worker {
  pid_t pid = -1;
  int fd = -1;
  std::string pending;  // bytes after the last full line
};

}  // namespace

int BatchSummary::Failed() const {
  int n = 0;
  for (const BatchJobResult& j : jobs) n += j.error.empty() ? 0 : 1;
  return n;
}

BatchJobResult RunJob(const BatchJob& job, std::size_t index, double sim_seconds,
                      const WorldFactory& make_world, const std::function<void(double)>& report) {
  BatchJobResult r;
  r.index = index;
  r.seed = job.seed;
  r.world = job.world.string();
  try {
    std::unique_ptr<World> world = make_world(job);
    r.world = world->model().name;
    bench::RandomPlay play(*world, job.seed);
    const auto steps = static_cast<std::int64_t>(std::llround(sim_seconds / world->clock().step_seconds()));
    const std::int64_t report_every = std::max<std::int64_t>(1, steps / 100);
    const auto t0 = SteadyClock::now();
    for (std::int64_t i = 0; i < steps; ++i) {
      play.BeforeStep();
      world->Step();
      if (report && i % report_every == 0) report(static_cast<double>(i) / static_cast<double>(steps));
    }
    r.wall_seconds = std::chrono::duration<double>(SteadyClock::now() - t0).count();
    r.steps = steps;
    r.sim_seconds = world->clock().seconds();
    r.state_hash = world->StateHash();
  } catch (const std::exception& e) {
    r.error = e.what();
  }
  return r;
}

BatchSummary RunBatch(const BatchOptions& options, const WorldFactory& make_world,
                      const BatchProgress& progress) {
  BatchSummary summary;
  summary.workers = std::max(1, std::min<int>(options.workers, static_cast<int>(std::max<std::size_t>(1, options.jobs.size()))));
  BatchOptions o = options;
  o.workers = summary.workers;
  summary.jobs.resize(o.jobs.size());
  std::vector<bool> finished(o.jobs.size(), false);
  std::vector<double> fraction(o.jobs.size(), 0.0);
  for (std::size_t i = 0; i < o.jobs.size(); ++i) {
    summary.jobs[i].index = i;
    summary.jobs[i].seed = o.jobs[i].seed;
    summary.jobs[i].world = o.jobs[i].world.string();
  }

  std::fflush(nullptr);  // a forked child must not flush the parent's buffered output twice
  const auto t0 = SteadyClock::now();
  std::vector<Worker> workers(static_cast<std::size_t>(o.workers));
  for (int w = 0; w < o.workers; ++w) {
    int fds[2];
    if (::pipe(fds) != 0) throw std::runtime_error(std::string("batch: pipe: ") + std::strerror(errno));
    const pid_t pid = ::fork();
    if (pid < 0) throw std::runtime_error(std::string("batch: fork: ") + std::strerror(errno));
    if (pid == 0) {
      ::close(fds[0]);
      for (int other = 0; other < w; ++other) ::close(workers[static_cast<std::size_t>(other)].fd);
      WorkerMain(fds[1], w, o, make_world);
    }
    ::close(fds[1]);
    workers[static_cast<std::size_t>(w)] = Worker{pid, fds[0], {}};
  }

  std::size_t done = 0;
  auto handle_line = [&](const std::string& line) {
    std::istringstream in(line);
    char kind = 0;
    std::size_t i = 0;
    in >> kind >> i;
    if (i >= o.jobs.size()) return;
    BatchJobResult& r = summary.jobs[i];
    if (kind == 'P') {
      in >> fraction[i];
    } else if (kind == 'R') {
      in >> r.steps >> r.sim_seconds >> r.wall_seconds >> r.state_hash;
      std::getline(in >> std::ws, r.world);
      fraction[i] = 1.0;
      finished[i] = true;
      ++done;
    } else if (kind == 'E') {
      std::getline(in >> std::ws, r.error);
      fraction[i] = 1.0;
      finished[i] = true;
      ++done;
    }
  };
  auto report = [&] {
    if (!progress) return;
    double sum = 0;
    for (double f : fraction) sum += f;
    progress(done, o.jobs.size(), o.jobs.empty() ? 1.0 : sum / static_cast<double>(o.jobs.size()));
  };

  std::size_t open = workers.size();
  while (open > 0) {
    std::vector<pollfd> fds;
    std::vector<std::size_t> which;
    for (std::size_t w = 0; w < workers.size(); ++w) {
      if (workers[w].fd >= 0) {
        fds.push_back(pollfd{workers[w].fd, POLLIN, 0});
        which.push_back(w);
      }
    }
    if (::poll(fds.data(), fds.size(), 200) < 0 && errno != EINTR) break;
    for (std::size_t k = 0; k < fds.size(); ++k) {
      if (!(fds[k].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      Worker& w = workers[which[k]];
      char buffer[4096];
      const ssize_t n = ::read(w.fd, buffer, sizeof buffer);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        ::close(w.fd);
        w.fd = -1;
        --open;
        continue;
      }
      w.pending.append(buffer, static_cast<std::size_t>(n));
      std::size_t newline;
      while ((newline = w.pending.find('\n')) != std::string::npos) {
        handle_line(w.pending.substr(0, newline));
        w.pending.erase(0, newline + 1);
      }
    }
    report();
  }

  // A worker that died leaves its remaining jobs unfinished: say so, with how it ended.
  for (int w = 0; w < o.workers; ++w) {
    int status = 0;
    ::waitpid(workers[static_cast<std::size_t>(w)].pid, &status, 0);
    std::string how;
    if (WIFSIGNALED(status)) {
      how = "worker process killed by signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
    } else if (WIFEXITED(status) && WEXITSTATUS(status) != 0) {
      how = "worker process exited with status " + std::to_string(WEXITSTATUS(status));
    } else {
      how = "worker process ended before reporting";
    }
    for (std::size_t i = static_cast<std::size_t>(w); i < o.jobs.size(); i += static_cast<std::size_t>(o.workers)) {
      if (!finished[i]) {
        summary.jobs[i].error = how;
        finished[i] = true;
        ++done;
      }
    }
  }
  summary.wall_seconds = std::chrono::duration<double>(SteadyClock::now() - t0).count();
  for (const BatchJobResult& r : summary.jobs) {
    if (r.error.empty()) summary.sim_seconds += r.sim_seconds;
  }
  report();
  return summary;
}

}  // namespace ubersim::kernel::batch
