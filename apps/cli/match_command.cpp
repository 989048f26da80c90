// SPDX-License-Identifier: Apache-2.0
// `ubersim match [WORLD] --yellow CMD --blue CMD`: a refereed match between two teams' programs.
// Starts the world, the referee (built-in or a game controller), and both programs with the
// match's settings in their environment; runs until the match is over, the duration is reached, or
// a team's program ends or stops sending commands; then stops everything and writes the result.
#include <atomic>
#include <chrono>
#include <csignal>
#include <fstream>
#include <iostream>
#include <optional>

#include <rapidjson/ostreamwrapper.h>
#include <rapidjson/prettywriter.h>

#include "ubersim/kernel/data_paths.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/runner.hpp"
#include "ubersim/kernel/world.hpp"
#include "command_line.hpp"
#include "commands.hpp"
#include "exit_codes.hpp"
#include "match_flags.hpp"
#include "run_overrides.hpp"
#include "team_process.hpp"
#include "world_loading.hpp"

namespace ubersim::cli {
namespace {

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace ubersim::kernel;

std::atomic<bool>& MatchInterrupted() {
  static std::atomic<bool> stop{false};
  return stop;
}
extern "C" void OnMatchSignal(int) { MatchInterrupted().store(true); }

struct MatchCommandFlags {
  std::string world_arg, yellow, blue, result = "match-result.json", team_output;
  double duration = 0, speed = 1.0, team_timeout = 10.0;
  std::vector<std::string> plugin_paths;
  std::string log_level = "warning";
  RunOverrides overrides;
  MatchFlags match;
};

// A transport's integer parameter after the overrides (its schema's default when unset).
int TransportInt(const WorldModel& model, const std::string& plugin, const std::string& key, int fallback) {
  for (const TransportModel& t : model.transports) {
    if (t.plugin == plugin) return static_cast<int>(t.params.GetInt(key, fallback));
  }
  return fallback;
}
std::string TransportText(const WorldModel& model, const std::string& plugin, const std::string& key,
                          const std::string& fallback) {
  for (const TransportModel& t : model.transports) {
    if (t.plugin == plugin) return t.params.GetString(key, fallback);
  }
  return fallback;
}

// What a team's program is told (environment), and the same as {placeholders} in its command.
std::vector<std::pair<std::string, std::string>> TeamEnvironment(const WorldModel& model, const MatchFlags& m,
                                                                  const std::string& color) {
  const int vision = TransportInt(model, "ssl_vision", "port", 10020);
  const int own = TransportInt(model, "ssl_simulation", color == "blue" ? "blue_port" : "yellow_port",
                               color == "blue" ? 10301 : 10302);
  return {{"UBERSIM_TEAM_COLOR", color},
          {"UBERSIM_VISION_ADDRESS", TransportText(model, "ssl_vision", "address", "224.5.23.2")},
          {"UBERSIM_VISION_PORT", std::to_string(vision)},
          {"UBERSIM_REFEREE_ADDRESS", "224.5.23.1"},
          {"UBERSIM_REFEREE_PORT", std::to_string(m.referee_port)},
          {"UBERSIM_TRACKER_PORT", std::to_string(m.tracker_port)},
          {"UBERSIM_CONTROL_PORT", std::to_string(own)},
          {"UBERSIM_SIMULATION_CONTROL_PORT", std::to_string(TransportInt(model, "ssl_simulation", "control_port", 10300))},
          {"UBERSIM_GRSIM_PORT", std::to_string(TransportInt(model, "grsim", "port", 20011))}};
}

// `command` with {color}, {vision_port}, {control_port}, … replaced by the environment's values.
std::string Expand(std::string command, const std::vector<std::pair<std::string, std::string>>& env) {
  for (const auto& [key, value] : env) {
    std::string name = key.substr(std::string("UBERSIM_").size());
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (name == "team_color") name = "color";
    const std::string placeholder = "{" + name + "}";
    for (std::size_t at = command.find(placeholder); at != std::string::npos; at = command.find(placeholder, at)) {
      command.replace(at, placeholder.size(), value);
      at += value.size();
    }
  }
  return command;
}

// Robot commands received from the match's team `i` (0 yellow, 1 blue; the kernel counts blue first).
std::int64_t CommandsFrom(const World& world, int i) { return world.event_counters().commands_received[i == 0 ? 1 : 0]; }

struct TeamWatch {
  std::unique_ptr<match::TeamProcess> process;
  std::string command;
  std::int64_t last_commands = 0;
  std::int64_t last_heard_ns = 0;
  std::optional<std::string> ended;
};

void WriteResult(const fs::path& file, const MatchCommandFlags& f, const WorldModel& model, const World& world,
                 const match::MatchSession& session, TeamWatch teams[2], const std::string& outcome,
                 const std::string& reason, double wall_seconds) {
  std::ofstream out(file);
  if (!out) throw std::runtime_error("cannot write the match result " + file.string());
  rapidjson::OStreamWrapper os(out);
  rapidjson::PrettyWriter<rapidjson::OStreamWrapper> w(os);
  w.StartObject();
  w.Key("world");
  w.String(model.name.c_str());
  w.Key("world_file");
  w.String(model.file.c_str());
  w.Key("referee");
  w.String(f.match.referee.c_str());
  w.Key("outcome");
  w.String(outcome.c_str());
  w.Key("reason");
  w.String(reason.c_str());
  w.Key("sim_time");
  w.Double(world.clock().seconds());
  w.Key("wall_time");
  w.Double(wall_seconds);
  w.Key("steps");
  w.Int64(world.clock().steps());
  const match::RefereeEngine* referee = session.referee();
  if (referee != nullptr) {
    const Referee& m = referee->message();
    w.Key("stage");
    w.String(Referee::Stage_Name(m.stage()).c_str());
    w.Key("command");
    w.String(Referee::Command_Name(m.command()).c_str());
  }
  const char* colors[2] = {"yellow", "blue"};
  for (int i = 0; i < 2; ++i) {
    w.Key(colors[i]);
    w.StartObject();
    w.Key("program");
    w.String(teams[i].command.c_str());
    w.Key("ended");
    if (teams[i].ended) {
      w.String(teams[i].ended->c_str());
    } else {
      w.Null();
    }
    w.Key("commands_received");
    w.Int64(CommandsFrom(world, i));
    if (referee != nullptr) {
      const Referee::TeamInfo& t = i == 0 ? referee->message().yellow() : referee->message().blue();
      w.Key("name");
      w.String(t.name().c_str());
      w.Key("score");
      w.Uint(t.score());
      w.Key("yellow_cards");
      w.Uint(t.yellow_cards());
      w.Key("red_cards");
      w.Uint(t.red_cards());
      w.Key("fouls");
      w.Uint(t.foul_counter());
      w.Key("ball_placement_failures");
      w.Uint(t.ball_placement_failures());
    }
    w.EndObject();
  }
  w.Key("events");
  w.StartArray();
  if (referee != nullptr) {
    for (std::size_t i = 0; i < referee->history().size(); ++i) {
      const GameEvent& e = referee->history()[i];
      w.StartObject();
      w.Key("time");
      w.Double(static_cast<double>(referee->history_times()[i]) * 1e-9);
      w.Key("type");
      w.String(GameEvent::Type_Name(e.type()).c_str());
      w.EndObject();
    }
  }
  w.EndArray();
  w.Key("record");
  if (f.match.record.empty()) {
    w.Null();
  } else {
    w.String(f.match.record.c_str());
  }
  w.EndObject();
  out << "\n";
}

}  // namespace

int MatchCommand(const std::vector<std::string>& args) {
  MatchCommandFlags f;
  po::options_description desc(
      "usage: ubersim match [WORLD] --yellow CMD --blue CMD [options]\n\n"
      "Plays a refereed match between two teams' programs on WORLD (default div-b): starts the world, the\n"
      "referee (--referee builtin, the default, or gc) and each program as `/bin/sh -c CMD` with its colour\n"
      "and the ports in its environment (UBERSIM_TEAM_COLOR, UBERSIM_VISION_PORT, UBERSIM_REFEREE_PORT,\n"
      "UBERSIM_CONTROL_PORT, …; the same names in lower case as {color}, {vision_port}, {control_port}, … in\n"
      "CMD). Runs until the match is over, --duration, Ctrl-C, or a program ends or sends no robot command\n"
      "for --team-timeout simulated seconds; then stops the programs and writes the result (score, events,\n"
      "timings) as JSON (docs/match.md).\n\noptions");
  desc.add_options()("help,h", "this help")
      ("yellow", po::value<std::string>(&f.yellow), "the yellow team's program (a shell command)")
      ("blue", po::value<std::string>(&f.blue), "the blue team's program (a shell command)")
      ("result", po::value<std::string>(&f.result)->default_value("match-result.json"), "where the result goes (JSON)")
      ("team-output", po::value<std::string>(&f.team_output), "directory for the programs' output (yellow.log, blue.log); default: this terminal")
      ("team-timeout", po::value<double>(&f.team_timeout)->default_value(10.0),
       "a team that sends no robot command for this many simulated seconds has stopped answering (0: never)")
      ("duration", po::value<double>(&f.duration)->default_value(0), "stop after SECONDS of simulated time (0: at the end of the match)")
      ("fast", "as fast as possible instead of real time (the programs must keep up)")
      ("sync", "synchronous: as fast as the teams keep up; after each camera frame period the world waits until both "
               "programs have sent a robot command (up to --team-timeout wall seconds)")
      ("speed", po::value<double>(&f.speed)->default_value(1.0), "speed factor (sim s per wall s)")
      ("local-only", "keep everything on loopback (127.0.0.1)")
      ("no-viewer", "do not start the browser viewer")
      ("plugin-path", po::value<std::vector<std::string>>(&f.plugin_paths), "also search DIR for plugins (repeatable)")
      ("log-level", po::value<std::string>(&f.log_level)->default_value("warning"), "debug, info, warning or error");
  AddPortFlags(desc);
  po::options_description match("match (docs/match.md)");
  f.match.AddTo(match);
  desc.add(match);
  po::options_description hidden;
  hidden.add_options()("world", po::value<std::string>(&f.world_arg));
  po::positional_options_description pos;
  pos.add("world", 1);
  po::variables_map vm;
  if (const auto done = ParseCommandLine(args, "match", desc, vm, &hidden, &pos)) return *done;
  if (f.yellow.empty() || f.blue.empty()) throw UsageError("give both teams' programs: --yellow CMD --blue CMD");
  if (f.duration < 0 || f.speed < 0 || f.team_timeout < 0) throw UsageError("--duration, --speed and --team-timeout must be >= 0");
  // The world's match: block, then: a match is refereed.
  const bool referee_given = !vm["referee"].defaulted();
  StreamLog log(std::cerr, LogLevelOf(f.log_level));

  const fs::path world_file = f.world_arg.empty() ? DefaultWorldFile() : WorldFileOf(f.world_arg);
  LoadedWorld loaded = LoadWorldWithPlugins(world_file, f.plugin_paths);
  WorldModel& model = loaded.model;
  f.match.FromWorld(model.match, vm);
  if (!referee_given && f.match.referee == "none") f.match.referee = "builtin";
  if (f.match.referee == "none") throw UsageError("--referee none: a match needs a referee (builtin or gc)");
  f.overrides.local_only = vm.count("local-only") > 0;
  if (!vm["referee-port"].defaulted()) f.overrides.viewer_referee_port = f.match.referee_port;
  ReadPortFlags(vm, f.overrides.ports);
  if (vm.count("no-viewer")) std::erase_if(model.transports, [](const TransportModel& t) { return t.plugin == "viewer"; });
  for (const std::string& note : ApplyRunOverrides(f.overrides, model, loaded.loading.loader, *loaded.loading.registry)) {
    std::cerr << "ubersim: " << note << "\n";
  }
  World world(model, *loaded.loading.registry, log);
  std::unique_ptr<sslog::LogWriter> record;
  match::MatchSession session(world, f.match.Options(model, f.overrides.local_only, record), log);
  std::cerr << "ubersim: match on '" << model.name << "', referee " << f.match.referee << "\n";
  for (const auto& e : world.TransportEndpoints()) std::cerr << "ubersim: publishing " << e << "\n";
  for (const auto& e : session.Endpoints()) std::cerr << "ubersim: publishing " << e << "\n";

  if (!f.team_output.empty()) fs::create_directories(f.team_output);
  TeamWatch teams[2];
  const char* colors[2] = {"yellow", "blue"};
  const std::string* commands[2] = {&f.yellow, &f.blue};
  for (int i = 0; i < 2; ++i) {
    const auto env = TeamEnvironment(model, f.match, colors[i]);
    teams[i].command = Expand(*commands[i], env);
    const std::string out = f.team_output.empty() ? "" : (fs::path(f.team_output) / (std::string(colors[i]) + ".log")).string();
    teams[i].process = std::make_unique<match::TeamProcess>(colors[i], teams[i].command, env, out);
    std::cerr << "ubersim: " << colors[i] << " team: " << teams[i].command << " (pid " << teams[i].process->pid() << ")\n";
  }

  std::signal(SIGINT, OnMatchSignal);
  std::signal(SIGTERM, OnMatchSignal);
  std::atomic<bool> stop{false};
  std::string outcome = "completed", reason;
  const auto wall_start = std::chrono::steady_clock::now();
  auto next_check = wall_start;
  RunOptions options;
  options.duration = f.duration;
  const bool sync = vm.count("sync") > 0;
  options.speed_factor = vm.count("fast") || sync ? 0.0 : f.speed;
  // Synchronous: one frame period of the cameras per round of commands from both teams.
  const auto frame_ns = static_cast<std::int64_t>(1e9 / std::max(1.0, world.perception().frame_rate));
  std::int64_t next_sync_ns = world.clock().time_ns() + frame_ns;
  std::int64_t synced[2] = {0, 0};
  options.status_interval = 5.0;
  options.between_steps = [&] {
    if (stop.load()) return;
    try {
      session.AfterStep();
    } catch (const std::exception& e) {  // the game controller went away
      outcome = "error";
      reason = e.what();
      stop.store(true);
      return;
    }
    if (MatchInterrupted().load()) {
      outcome = "interrupted";
      reason = "interrupted (SIGINT or SIGTERM)";
      stop.store(true);
      return;
    }
    if (session.referee() != nullptr && session.referee()->finished()) {
      reason = "the match is over";
      stop.store(true);
      return;
    }
    if (sync && world.clock().time_ns() >= next_sync_ns) {
      const auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(f.team_timeout > 0 ? f.team_timeout : 1e9);
      for (;;) {
        world.ProcessEvents();  // commands are counted as they are applied
        const bool yellow_late = CommandsFrom(world, 0) <= synced[0];
        const bool blue_late = CommandsFrom(world, 1) <= synced[1];
        if (!yellow_late && !blue_late) break;
        for (int i = 0; i < 2; ++i) {
          if (!teams[i].ended) teams[i].ended = teams[i].process->Ended();
        }
        if (teams[0].ended || teams[1].ended || std::chrono::steady_clock::now() > give_up || MatchInterrupted().load()) {
          if (MatchInterrupted().load()) break;
          const int late = teams[0].ended ? 0 : teams[1].ended ? 1 : yellow_late ? 0 : 1;
          outcome = "team failed";
          reason = teams[late].ended ? std::string(colors[late]) + " team's program ended (" + *teams[late].ended + ")"
                                     : std::string(colors[late]) + " team did not answer within " +
                                           std::to_string(f.team_timeout) + " s (synchronous mode)";
          reason += " at " + std::to_string(world.clock().seconds()) + " s";
          stop.store(true);
          return;
        }
        world.events().WaitForEvent(std::chrono::milliseconds(1));
      }
      synced[0] = CommandsFrom(world, 0);
      synced[1] = CommandsFrom(world, 1);
      next_sync_ns += frame_ns;
    }
    const auto now = std::chrono::steady_clock::now();
    if (now < next_check) return;
    next_check = now + std::chrono::milliseconds(50);
    for (int i = 0; i < 2; ++i) {
      TeamWatch& t = teams[i];
      if (const auto ended = t.process->Ended()) {
        t.ended = ended;
        outcome = "team failed";
        reason = std::string(colors[i]) + " team's program ended (" + *ended + ") at " +
                 std::to_string(world.clock().seconds()) + " s";
        stop.store(true);
        return;
      }
      const std::int64_t received = CommandsFrom(world, i);
      if (received != t.last_commands) {
        t.last_commands = received;
        t.last_heard_ns = world.clock().time_ns();
      }
      const double silent = static_cast<double>(world.clock().time_ns() - t.last_heard_ns) * 1e-9;
      if (f.team_timeout > 0 && silent > f.team_timeout) {
        outcome = "team failed";
        reason = std::string(colors[i]) + " team sent no robot command for " + std::to_string(f.team_timeout) +
                 " s (simulated) at " + std::to_string(world.clock().seconds()) + " s";
        stop.store(true);
        return;
      }
    }
  };
  RunWorld(world, options, stop, [](const RunStatus&) {});
  if (reason.empty()) reason = world.stopped() ? "a plugin fault stopped the world" : "the duration was reached";
  if (world.stopped()) outcome = "error";
  for (TeamWatch& t : teams) {
    if (!t.ended) t.process->Stop();
  }
  if (record) record->Close();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  WriteResult(f.result, f, model, world, session, teams, outcome, reason, wall);
  if (session.referee() != nullptr) {
    const Referee& m = session.referee()->message();
    std::cerr << "ubersim: " << m.yellow().name() << " (yellow) " << m.yellow().score() << " : " << m.blue().score() << " "
              << m.blue().name() << " (blue), " << Referee::Stage_Name(m.stage()) << "; " << reason << "\n";
  }
  std::cerr << "ubersim: result written to " << f.result << "\n";
  if (outcome == "team failed") return kExitTeamFailed;
  return outcome == "error" ? kExitRuntime : kExitOk;
}

}  // namespace ubersim::cli
