// SPDX-License-Identifier: Apache-2.0
#include "ubersim/kernel/runner.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "ubersim/kernel/snapshot.hpp"
#include "ubersim/kernel/world.hpp"

namespace ubersim::kernel {
namespace {

constexpr int kFatalSignals[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
constexpr std::size_t kSignalCount = sizeof kFatalSignals / sizeof kFatalSignals[0];

// Everything the handler touches, built before it can run.
struct FatalSignalState {
  struct Slot {
    std::vector<char> snapshot;  // a snapshot file's bytes
    std::string tail;            // the report's lines about it
  };
  Slot slots[2];
  std::atomic<int> published{-1};    // the slot a crash writes; -1: none yet
  std::atomic<bool> crashing{false};  // a handler runs: Update keeps its hands off the slots
  std::string report_path, snapshot_path;
  std::string head;         // the report up to the signal line
  std::string no_snapshot;  // the tail before the first Update
  std::vector<char> alt_stack;
  struct sigaction previous[kSignalCount];
  bool installed = false;
};

// The one guard installed: a signal handler can reach nothing but globals. (Besides the run
// loop's stop flag, the only process-wide state ubersim has.)
std::atomic<FatalSignalState*> g_guard{nullptr};

void WriteAll(int fd, const char* data, std::size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd, data, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return;
    data += w;
    n -= static_cast<std::size_t>(w);
  }
}
void WriteText(int fd, const char* text) { WriteAll(fd, text, std::strlen(text)); }

const char* SignalName(int sig) {
  switch (sig) {
    case SIGSEGV: return "SIGSEGV (invalid memory access)";
    case SIGBUS: return "SIGBUS (bus error)";
    case SIGFPE: return "SIGFPE (arithmetic exception)";
    case SIGILL: return "SIGILL (illegal instruction)";
    case SIGABRT: return "SIGABRT (abort: a failed assertion or an uncaught exception)";
    default: return "a fatal signal";
  }
}

// Async-signal-safe from here: open, write, close, sigaction, raise; no allocation, no locks.
extern "C" void OnFatalSignal(int sig, siginfo_t*, void*) {
  FatalSignalState* s = g_guard.load();
  if (s && !s->crashing.exchange(true)) {
    const int slot = s->published.load();
    int fd = ::open(s->report_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd >= 0) {
      WriteAll(fd, s->head.data(), s->head.size());
      WriteText(fd, "fatal signal: ");
      WriteText(fd, SignalName(sig));
      WriteText(fd, "\n");
      const std::string& tail = slot >= 0 ? s->slots[slot].tail : s->no_snapshot;
      WriteAll(fd, tail.data(), tail.size());
      ::close(fd);
    }
    if (slot >= 0) {
      fd = ::open(s->snapshot_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
      if (fd >= 0) {
        WriteAll(fd, s->slots[slot].snapshot.data(), s->slots[slot].snapshot.size());
        ::close(fd);
      }
    }
  }
  // Then what the signal would have done without us: the default action, for this signal.
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  ::sigaction(sig, &dfl, nullptr);
  ::raise(sig);
}

std::string UtcNow(const char* format) {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char text[32];
  std::strftime(text, sizeof text, format, &tm);
  return text;
}

std::string Head(const RunDescription& run, const char* title) {
  std::ostringstream out;
  out << "ÜberSim crash report: " << title << "\n"
      << "program: " << run.program << "\n"
      << "world:   " << run.world_name << " (" << run.world_file << ")\n"
      << "command: " << run.command_line << "\n";
  return out.str();
}

std::string Seconds(std::int64_t ns) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f", 1e-9 * static_cast<double>(ns));
  return text;
}

std::string ResumeLine(const RunDescription& run, const std::filesystem::path& snapshot) {
  return "resume:  ubersim run " + run.world_file + " --restore " + snapshot.string() + "\n";
}

}  // namespace

CrashFiles CrashFilesIn(const std::filesystem::path& dir, const std::string& world_name) {
  std::string name;
  for (char c : world_name) name.push_back(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_');
  const std::string stem = "ubersim-crash-" + name + "-" + UtcNow("%Y%m%dT%H%M%SZ") + "-" + std::to_string(::getpid());
  return CrashFiles{dir / (stem + ".txt"), dir / (stem + ".snapshot")};
}

void WriteFaultReport(const World& world, const CrashFiles& files, const RunDescription& run) {
  std::ostringstream out;
  out << Head(run, "a plugin fault stopped the world") << "written: " << UtcNow("%Y-%m-%dT%H:%M:%SZ") << "\n"
      << "stopped: "
      << (world.clock().steps() == 0 ? std::string("before the first step (a fault while building)")
                                     : "after step " + std::to_string(world.clock().steps() - 1))
      << " (sim time " << Seconds(world.clock().time_ns()) << " s), on_plugin_fault: " << ToString(world.fault_policy())
      << "\n"
      << "faults:\n";
  for (const PluginFault& f : world.faults()) {
    out << "  step " << f.step << " (sim time " << Seconds(f.sim_time_ns) << " s): " << f.Describe() << "\n";
  }
  std::string snapshot_note;
  try {
    WriteSnapshotFile(files.snapshot, world.Save());
    out << "snapshot: " << files.snapshot.string()
        << " (the world after that step; the faulty plugin is saved switched off)\n"
        << ResumeLine(run, files.snapshot);
  } catch (const std::exception& e) {
    out << "snapshot: none: " << e.what() << "\n";
  }
  std::ofstream file(files.report);
  file << out.str();
  file.close();
  if (!file) throw std::runtime_error("cannot write the crash report " + files.report.string() + ": " + std::strerror(errno));
}

struct CrashGuard::State : FatalSignalState {};

CrashGuard::CrashGuard(CrashFiles files, RunDescription run)
    : files_(std::move(files)), run_(std::move(run)), state_(std::make_unique<State>()) {
  state_->report_path = files_.report.string();
  state_->snapshot_path = files_.snapshot.string();
  state_->head = Head(run_, "the process died") + "written: at the crash (the file's time)\n";
  state_->no_snapshot = "snapshot: none yet (the first is taken after the first simulated second)\n";
}

CrashGuard::~CrashGuard() {
  if (!state_->installed) return;
  for (std::size_t i = 0; i < kSignalCount; ++i) ::sigaction(kFatalSignals[i], &state_->previous[i], nullptr);
  g_guard.store(nullptr);
  stack_t none{};
  none.ss_flags = SS_DISABLE;
  ::sigaltstack(&none, nullptr);
}

void CrashGuard::Install() {
  if (state_->installed) return;
  FatalSignalState* expected = nullptr;
  if (!g_guard.compare_exchange_strong(expected, state_.get())) {
    throw std::logic_error("a crash guard is installed already");
  }
  state_->alt_stack.resize(1 << 16);
  stack_t stack{};
  stack.ss_sp = state_->alt_stack.data();
  stack.ss_size = state_->alt_stack.size();
  ::sigaltstack(&stack, nullptr);
  struct sigaction action {};
  action.sa_sigaction = OnFatalSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_SIGINFO | SA_ONSTACK | SA_NODEFER;
  for (std::size_t i = 0; i < kSignalCount; ++i) ::sigaction(kFatalSignals[i], &action, &state_->previous[i]);
  state_->installed = true;
}

void CrashGuard::Update(const World& world) {
  if (state_->crashing.load()) return;
  std::string bytes;
  try {
    bytes = EncodeSnapshot(world.Save());
  } catch (const std::exception&) {
    return;  // keep the previous one
  }
  const int spare = state_->published.load() == 0 ? 1 : 0;
  FatalSignalState::Slot& slot = state_->slots[spare];
  slot.snapshot.assign(bytes.begin(), bytes.end());
  slot.tail = "snapshot: " + files_.snapshot.string() + " (the last one taken, of step " +
              std::to_string(world.clock().steps()) + ", sim time " + Seconds(world.clock().time_ns()) + " s)\n" +
              ResumeLine(run_, files_.snapshot);
  state_->published.store(spare);
  snapshot_step_ = world.clock().steps();
}

}  // namespace ubersim::kernel
