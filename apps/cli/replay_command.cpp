// SPDX-License-Identifier: Apache-2.0
// `ubersim replay FILE`: plays an SSL log file (apps/sslog, docs/log-files.md) back onto the
// league's multicast groups, one datagram per record, paced by the records' timestamps, as the
// league's ssl-log-player does; with --viewer, shows it in the browser viewer with a time slider
// (replay_viewer.hpp), sending it too with --send; or, with --info, says what the file holds.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "command_line.hpp"
#include "commands.hpp"
#include "exit_codes.hpp"
#include "replay_timeline.hpp"
#include "replay_viewer.hpp"
#include "ssl_log.hpp"
#include "transport_common/multicast_sender.hpp"
#include "ubersim/kernel/logging.hpp"

namespace ubersim::cli {

namespace po = boost::program_options;

namespace {

using sslog::LogReader;
using sslog::LogRecord;
using SteadyClock = std::chrono::steady_clock;

// Set by SIGINT / SIGTERM: the replay stops between two datagrams and prints its summary.
volatile std::sig_atomic_t g_stop = 0;
extern "C" void OnStopSignal(int) { g_stop = 1; }

// Longest sleep between two looks at g_stop.
constexpr auto kStopPoll = std::chrono::milliseconds(50);

// SIGINT and SIGTERM set g_stop while it lives.
struct StopOnSignal {
  StopOnSignal() {
    g_stop = 0;
    std::signal(SIGINT, OnStopSignal);
    std::signal(SIGTERM, OnStopSignal);
  }
  ~StopOnSignal() {
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
  }
  StopOnSignal(const StopOnSignal&) = delete;
  StopOnSignal& operator=(const StopOnSignal&) = delete;
};

// `value` as printf's %g writes it: "1", "0.5", "-2".
std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

// Where the records of one message type go.
struct Destination {
  std::int32_t type;
  const char* what;  // for the summary: "vision"
  const char* group;
  std::uint16_t port;
  std::unique_ptr<transport::MulticastSender> sender;
  std::uint64_t sent = 0;
  bool warned = false;  // a failed send was reported
};

// Every record read, by type, and the span of their timestamps (the index's 0 left out).
struct Summary {
  std::map<std::int32_t, std::uint64_t> per_type;
  std::uint64_t records = 0;
  std::optional<std::int64_t> first_ns, last_ns;
  std::uint64_t steps_back = 0;  // timestamps below the one before
  std::optional<std::size_t> index_entries;

  void Add(const LogRecord& r) {
    ++records;
    ++per_type[r.type];
    if (r.type == static_cast<std::int32_t>(sslog::MessageType::kIndex2021)) {
      if (const auto offsets = sslog::ParseIndexPayload(r.payload)) index_entries = offsets->size();
      return;
    }
    if (last_ns && r.timestamp_ns < *last_ns) ++steps_back;
    if (!first_ns) first_ns = r.timestamp_ns;
    last_ns = r.timestamp_ns;
  }
};

// "12.345 s".
std::string Seconds(double seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f s", seconds);
  return text;
}

// "1700000000123456789 ns (2023-11-14 22:13:20.123 UTC)".
std::string Timestamp(std::int64_t ns) {
  std::string out = std::to_string(ns) + " ns";
  const std::time_t seconds = static_cast<std::time_t>(ns / 1'000'000'000);
  std::tm utc{};
  if (ns >= 0 && gmtime_r(&seconds, &utc)) {
    char text[64];
    const std::size_t n = std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S", &utc);
    char millis[8];
    std::snprintf(millis, sizeof millis, ".%03d", static_cast<int>(ns / 1'000'000 % 1000));
    out += " (" + std::string(text, n) + millis + " UTC)";
  }
  return out;
}

void PrintSummary(const LogReader& reader, const Summary& s, std::ostream& out) {
  out << "file:       " << reader.Path() << (reader.Compressed() ? " (gzip)" : "") << "\n";
  out << "records:    " << s.records << "\n";
  for (const auto& [type, count] : s.per_type) {
    char line[96];
    std::snprintf(line, sizeof line, "  %-28s %10llu\n",
                  (sslog::MessageTypeName(type) + " (" + std::to_string(type) + ")").c_str(),
                  static_cast<unsigned long long>(count));
    out << line;
  }
  if (s.first_ns) {
    out << "first:      " << Timestamp(*s.first_ns) << "\n";
    out << "last:       " << Timestamp(*s.last_ns) << "\n";
    out << "duration:   " << Seconds(static_cast<double>(*s.last_ns - *s.first_ns) / 1e9) << "\n";
  }
  if (s.steps_back > 0) out << "timestamps: " << s.steps_back << " go back from the one before\n";
  if (s.index_entries) out << "index:      " << *s.index_entries << " record offsets\n";
}

// --info: reads the whole file; on a damaged file prints what it read, then lets the error out.
int Info(const std::string& file) {
  LogReader reader(file);
  Summary summary;
  try {
    while (const auto record = reader.Next()) summary.Add(*record);
  } catch (const sslog::LogFormatError&) {
    PrintSummary(reader, summary, std::cout);
    std::cout << "(the file is damaged after these records)\n";
    throw;
  }
  PrintSummary(reader, summary, std::cout);
  return kExitOk;
}

// Sleeps until `due`, waking early when a signal asks to stop.
void SleepUntil(SteadyClock::time_point due) {
  while (!g_stop) {
    const auto now = SteadyClock::now();
    if (now >= due) return;
    std::this_thread::sleep_for(std::min<SteadyClock::duration>(due - now, kStopPoll));
  }
}

// Sends `record` if its type has a destination; true if it had one (sent or refused).
bool SendTo(std::vector<Destination>& destinations, const LogRecord& record) {
  for (Destination& d : destinations) {
    if (d.type != record.type) continue;
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(record.payload.data());
    if (d.sender->Send({bytes, record.payload.size()})) {
      ++d.sent;
    } else if (!d.warned) {
      std::cerr << "ubersim replay: cannot send " << d.what << " to " << d.group << ":" << d.port << ": "
                << d.sender->LastError() << " (reported once)\n";
      d.warned = true;
    }
    return true;
  }
  return false;
}

// One pass over `file`: sends what has a destination, paced by `speed` (0: no pacing). Returns
// how many datagrams it tried to send (sent or refused); counts what it skipped by type.
std::uint64_t PlayOnce(const std::string& file, double speed, std::vector<Destination>& destinations,
                       std::map<std::int32_t, std::uint64_t>& skipped) {
  LogReader reader(file);
  std::optional<std::int64_t> first_ns;
  SteadyClock::time_point start;
  std::uint64_t tried = 0;
  while (!g_stop) {
    const std::optional<LogRecord> record = reader.Next();
    if (!record) break;
    const bool has_destination = std::any_of(destinations.begin(), destinations.end(),
                                             [&](const Destination& d) { return d.type == record->type; });
    if (!has_destination) {
      ++skipped[record->type];
      continue;
    }
    if (speed > 0) {
      // Due at the first datagram's time plus the recorded gap to it, over the speed: kept against
      // the start, so sleeping late for one datagram does not delay every later one.
      if (!first_ns) {
        first_ns = record->timestamp_ns;
        start = SteadyClock::now();
      }
      const double after_s = static_cast<double>(record->timestamp_ns - *first_ns) / 1e9 / speed;
      SleepUntil(start + std::chrono::duration_cast<SteadyClock::duration>(std::chrono::duration<double>(after_s)));
      if (g_stop) break;
    }
    SendTo(destinations, *record);
    ++tried;
  }
  return tried;
}

// "12.3 MB".
std::string Megabytes(std::size_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f MB", static_cast<double>(bytes) / 1e6);
  return text;
}

// True for an address that only this machine reaches (127.0.0.0/8, ::1).
bool IsLoopback(const std::string& address) { return address.rfind("127.", 0) == 0 || address == "::1"; }

// --viewer: loads the log, serves the page until Ctrl-C, sends it too when `destinations` is set.
int ShowInViewer(const std::string& file, const ReplayViewerOptions& options, std::vector<Destination>* destinations) {
  const auto loading = SteadyClock::now();
  const std::unique_ptr<LogTimeline> timeline = LogTimeline::Load(file);
  const LogTimeline::Counts& n = timeline->Count();
  std::cout << "loaded " << file << ": " << n.records << " records, "
            << Seconds(static_cast<double>(timeline->DurationNs()) / 1e9) << " (" << n.vision_frames
            << " camera frames, " << n.detections << " detections, " << n.referee_messages << " referee messages"
            << (n.tracked_frames > 0 ? ", " + std::to_string(n.tracked_frames) + " tracked frames (not shown)" : "")
            << ") in " << Seconds(std::chrono::duration<double>(SteadyClock::now() - loading).count()) << "; holds "
            << Megabytes(timeline->MemoryBytes()) << "\n";
  if (timeline->Damage()) {
    // The same located error as a replay onto the network gives; what came before it is shown.
    std::cout.flush();
    std::cerr << "ubersim replay: " << timeline->Damage()->what() << "\n";
    std::cout << "(the file is damaged after these records: showing what came before)\n";
  }
  if (n.geometries == 0) std::cout << "no geometry in the log: the field drawn is Division B's\n";
  if (timeline->Empty()) {
    std::cout << "nothing to replay: no record of types 2, 3, 4 or 5\n";
    return timeline->Damage() ? kExitRuntime : kExitOk;
  }
  std::cout.flush();

  const StopOnSignal stop_on_signal;
  kernel::StreamLog log(std::cerr, LogLevel::kWarning);
  const auto started = SteadyClock::now();
  SendRecord send;
  if (destinations) send = [destinations](const LogRecord& r) { SendTo(*destinations, r); };
  RunReplayViewer(
      *timeline, options, send, [] { return g_stop != 0; },
      [&](const std::string& url) {
        std::cout << "viewer: " << url << " (open it in a browser; Ctrl-C stops)" << std::endl;
      },
      log);
  if (destinations) {
    std::uint64_t sent = 0, failed = 0;
    std::string parts;
    for (const Destination& d : *destinations) {
      sent += d.sent;
      failed += d.sender->Failed();
      if (d.sent > 0) parts += std::string(parts.empty() ? "" : ", ") + d.what + " " + std::to_string(d.sent);
    }
    std::cout << "sent " << sent << " datagrams" << (parts.empty() ? "" : " (" + parts + ")") << " in "
              << Seconds(std::chrono::duration<double>(SteadyClock::now() - started).count()) << "\n";
    if (failed > 0) {
      std::cerr << "ubersim replay: " << failed << " datagrams were refused by the system\n";
      return kExitRuntime;
    }
  }
  std::cout.flush();
  return timeline->Damage() ? kExitRuntime : kExitOk;
}

}  // namespace

int ReplayCommand(const std::vector<std::string>& args) {
  po::options_description desc(
      "usage: ubersim replay FILE [options]\n\n"
      "Plays an SSL log file (.log, or gzip: .log.gz) back onto the network as the league's\n"
      "ssl-log-player does: each record's payload, unchanged, as one UDP datagram, paced by the\n"
      "records' timestamps. Vision (type 4) goes to 224.5.23.2:10006, tracked vision (5) to\n"
      "224.5.23.2:10010, referee (3) to 224.5.23.1:10003, legacy vision (2) to 224.5.23.2:10005;\n"
      "other types (the index among them) are skipped. --info says what the file holds instead.\n"
      "A file that cannot be read, or is damaged, ends the replay with exit code 1 and a message\n"
      "naming the record and its byte offset; the records before it have been sent.\n\n"
      "--viewer shows the log in the browser viewer instead, with a time slider (play, pause,\n"
      "speed, seek): the field from its geometry, robots and ball from the cameras' detections,\n"
      "the match from its referee messages. It sends nothing unless --send is given too; then the\n"
      "datagrams follow the slider. It serves the page until Ctrl-C.\n\noptions");
  std::string file;
  double speed = 1.0;
  bool local_only = false, loop = false, info = false, viewer = false, send = false;
  std::string viewer_address = "127.0.0.1";
  std::uint16_t viewer_port = 8080;
  std::vector<std::string> interfaces;
  std::uint16_t vision_port = 10006, tracker_port = 10010, referee_port = 10003, legacy_port = 10005;
  desc.add_options()("help,h", "this help")
      ("speed", po::value<double>(&speed)->default_value(1.0)->value_name("F"),
       "F times the recorded rate: 1 as recorded, 2 twice as fast, 0 as fast as possible")
      ("local-only", po::bool_switch(&local_only), "send on loopback only: receivers on this machine alone")
      ("interface", po::value<std::vector<std::string>>(&interfaces)->value_name("ADDR"),
       "send multicast out of the interface with address ADDR (repeatable; default: auto, loopback "
       "and the default route's interface)")
      ("loop", po::bool_switch(&loop), "start again at the end, until interrupted (Ctrl-C)")
      ("info", po::bool_switch(&info),
       "print the records per type, the first and last timestamp and the duration; send nothing")
      ("vision-port", po::value<std::uint16_t>(&vision_port)->value_name("PORT")->default_value(10006),
       "port of vision (type 4)")
      ("tracker-port", po::value<std::uint16_t>(&tracker_port)->value_name("PORT")->default_value(10010),
       "port of tracked vision (type 5)")
      ("referee-port", po::value<std::uint16_t>(&referee_port)->value_name("PORT")->default_value(10003),
       "port of the referee (type 3)")
      ("vision-legacy-port", po::value<std::uint16_t>(&legacy_port)->value_name("PORT")->default_value(10005),
       "port of legacy vision (type 2)")
      ("viewer", po::bool_switch(&viewer),
       "show the log in the browser viewer with a time slider (sends nothing without --send)")
      ("send", po::bool_switch(&send), "with --viewer: send the log too, in step with the slider")
      ("viewer-port", po::value<std::uint16_t>(&viewer_port)->value_name("PORT")->default_value(8080),
       "with --viewer: the page's port (0: any free one)")
      ("viewer-address", po::value<std::string>(&viewer_address)->value_name("ADDR")->default_value("127.0.0.1"),
       "with --viewer: the numeric address the page is served on (0.0.0.0: every interface; loopback "
       "only with --local-only)");
  po::options_description hidden;
  hidden.add_options()("file", po::value<std::string>(&file));
  po::positional_options_description pos;
  pos.add("file", 1);
  po::variables_map vm;
  if (const auto done = ParseCommandLine(args, "replay", desc, vm, &hidden, &pos)) return *done;
  if (file.empty()) {
    std::cerr << "ubersim replay: name the log file to replay\n\n" << desc << "\n";
    return kExitUsage;
  }
  if (!std::isfinite(speed) || speed < 0) {
    throw UsageError("--speed " + Number(speed) + ": must be 0 (as fast as possible) or more");
  }
  if (!viewer) {
    for (const char* flag : {"send", "viewer-port", "viewer-address"}) {
      if (!vm[flag].defaulted()) {
        throw UsageError(std::string("--") + flag + " is for --viewer (without it, replay sends the log anyway)");
      }
    }
  }
  if (viewer && (speed < 0.25 || speed > 8)) {
    throw UsageError("--speed " + Number(speed) + ": the viewer plays 0.25 to 8 times the recorded rate");
  }
  if (viewer && local_only && !IsLoopback(viewer_address)) {
    throw UsageError("--viewer-address " + viewer_address + " with --local-only: the page would be reachable "
                     "from other machines; leave it out (127.0.0.1) or drop --local-only");
  }
  if (info) return Info(file);

  { const LogReader check(file); }  // a missing or foreign file is named before any socket is opened
  if (viewer && !send) {
    std::cout << "showing " << file << " in the viewer; nothing is sent (add --send to send it too)\n";
    return ShowInViewer(file, ReplayViewerOptions{file, viewer_address, viewer_port, 60, speed, loop}, nullptr);
  }
  std::vector<Destination> destinations;
  destinations.push_back({4, "vision", "224.5.23.2", vision_port, nullptr});
  destinations.push_back({5, "tracked vision", "224.5.23.2", tracker_port, nullptr});
  destinations.push_back({3, "referee", "224.5.23.1", referee_port, nullptr});
  destinations.push_back({2, "legacy vision", "224.5.23.2", legacy_port, nullptr});
  for (Destination& d : destinations) {
    transport::MulticastSender::Options o;
    o.group = d.group;
    o.port = d.port;
    if (!interfaces.empty()) o.interfaces = interfaces;
    o.local_only = local_only;
    o.name = std::string("replay ") + d.what;
    d.sender = std::make_unique<transport::MulticastSender>(o);
    std::cout << d.what << " (type " << d.type << "): " << d.sender->Describe() << "\n";
  }
  if (viewer) {
    std::cout << "replaying " << file << " in the viewer and on the network, in step with the slider\n";
    return ShowInViewer(file, ReplayViewerOptions{file, viewer_address, viewer_port, 60, speed, loop}, &destinations);
  }
  std::cout << "replaying " << file << " at " << (speed > 0 ? "speed " + Number(speed) : std::string("full speed"))
            << (loop ? ", looping (Ctrl-C stops)" : "") << std::endl;

  const StopOnSignal stop_on_signal;
  const auto started = SteadyClock::now();
  std::map<std::int32_t, std::uint64_t> skipped;
  std::uint64_t passes = 0;
  const auto report = [&] {
    std::uint64_t sent = 0;
    std::string parts;
    for (const Destination& d : destinations) {
      sent += d.sent;
      if (d.sent > 0) parts += std::string(parts.empty() ? "" : ", ") + d.what + " " + std::to_string(d.sent);
    }
    const double seconds = std::chrono::duration<double>(SteadyClock::now() - started).count();
    std::cout << "sent " << sent << " datagrams" << (parts.empty() ? "" : " (" + parts + ")") << " in "
              << Seconds(seconds) << (passes > 1 ? ", " + std::to_string(passes) + " passes" : "") << "\n";
    for (const auto& [type, count] : skipped) {
      std::cout << "skipped " << count << " " << sslog::MessageTypeName(type) << " record" << (count == 1 ? "" : "s")
                << "\n";
    }
    std::cout.flush();
  };
  try {
    do {
      ++passes;
      if (PlayOnce(file, speed, destinations, skipped) == 0 && !g_stop) {
        report();
        std::cout << "nothing to replay: no record of types 2, 3, 4 or 5\n";
        return kExitOk;
      }
    } while (loop && !g_stop);
  } catch (const sslog::LogFormatError&) {
    report();
    throw;
  }
  report();
  std::uint64_t failed = 0;
  for (const Destination& d : destinations) failed += d.sender->Failed();
  if (failed > 0) {
    std::cerr << "ubersim replay: " << failed << " datagrams were refused by the system\n";
    return kExitRuntime;
  }
  return kExitOk;
}

}  // namespace ubersim::cli
