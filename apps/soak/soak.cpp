// SPDX-License-Identifier: Apache-2.0
#include "soak.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "shared/machine.hpp"
#include "shared/random_play.hpp"

namespace ubersim::kernel::soak {
namespace {

using SteadyClock = std::chrono::steady_clock;

// The teleports' own random stream, apart from the random play's (seeded with `seed` itself).
constexpr std::uint64_t kTeleportSeedMix = 0x9E3779B97F4A7C15ULL;

std::optional<Target> TargetOf(const StateObject& o) {
  if (o.kind == StateObject::Kind::kBall) return Target::Ball();
  if (o.kind == StateObject::Kind::kRobot) return Target::Robot(o.robot);
  return std::nullopt;
}

}  // namespace

SoakReport RunSoak(World& world, const SoakOptions& options, const std::function<void(const SoakProgress&)>& progress,
                   const std::function<void(const SoakFinding&)>& on_finding) {
  SoakReport report;
  report.world = world.model().name;
  report.max_rss_growth = options.max_rss_growth;
  report.warmup_seconds = options.warmup >= 0 ? options.warmup : std::min(300.0, options.sim_seconds / 5.0);

  apps::RandomPlay play(world, options.seed);
  RandomTeleports teleports(world, options.seed ^ kTeleportSeedMix, options.teleport_interval, options.wall_overlap);
  if (options.on_teleport) {
    teleports.SetObserver([&](const char* what, const PositionEvent& e) { options.on_teleport(world.clock().seconds(), what, e); });
  }
  const double dt = world.clock().step_seconds();
  const auto steps = static_cast<std::int64_t>(std::llround(options.sim_seconds / dt));
  const auto check_every = std::max<std::int64_t>(1, std::llround(options.check_period / dt));
  const auto grace_ns = static_cast<std::int64_t>(options.grace * 1e9);
  const auto recent = [&](const StateObject& o, std::int64_t now) {
    const std::optional<Target> t = TargetOf(o);
    return t && now - teleports.LastMoved(*t) < grace_ns;
  };

  // Robots seen leaning past the limit, and since when (ns): a rock is not a fall.
  std::map<std::string, std::int64_t> leaning_since;
  std::set<std::string> leaning_now;
  const auto tipped_for_ns = static_cast<std::int64_t>(options.tipped_for * 1e9);

  const auto start = SteadyClock::now();
  const auto check = [&] {
    ++report.checks;
    const std::int64_t now = world.clock().time_ns();
    const double t = world.clock().seconds();
    leaning_now.clear();
    for (StateViolation& v : CheckState(world, options.checks)) {
      // Right after a teleport the physics is still pushing the objects apart.
      if (v.issue == StateIssue::kInsideOther && (recent(v.object, now) || (v.other && recent(*v.other, now)))) continue;
      if (v.issue == StateIssue::kTipped) {
        leaning_now.insert(v.object.name);
        const std::int64_t since = leaning_since.try_emplace(v.object.name, now).first->second;
        if (now - since < tipped_for_ns) continue;
        leaning_since.erase(v.object.name);  // reported, and put back below
      }
      ++report.finding_count;
      ++report.by_issue[static_cast<int>(v.issue)];
      SoakFinding f{t, std::move(v)};
      if (on_finding) on_finding(f);
      if (f.violation.issue == StateIssue::kNonFinite) {
        report.stopped_early = true;  // every later step would carry the NaN on
      } else if (const std::optional<Target> target = TargetOf(f.violation.object)) {
        teleports.Replace(*target);
        ++report.replaced;
      }
      if (report.findings.size() < SoakReport::kKeptFindings) report.findings.push_back(std::move(f));
    }
    std::erase_if(leaning_since, [&](const auto& entry) { return !leaning_now.contains(entry.first); });
    const double rss = apps::ResidentMegabytes();
    if (t >= report.warmup_seconds) {
      if (report.rss_warm_mb == 0) report.rss_warm_mb = rss;
      report.rss_peak_mb = std::max(report.rss_peak_mb, rss);
      report.rss_end_mb = rss;
    }
    if (progress) {
      progress(SoakProgress{t, options.sim_seconds,
                            std::chrono::duration<double>(SteadyClock::now() - start).count(), rss,
                            report.finding_count});
    }
  };

  for (std::int64_t i = 1; i <= steps && !report.stopped_early; ++i) {
    if (play.BeforeStep()) teleports.MarkMoved(Target::Ball());
    teleports.BeforeStep();
    world.Step();
    if (options.after_step) options.after_step(world);
    if (i % check_every == 0 || i == steps) check();
  }
  report.wall_seconds = std::chrono::duration<double>(SteadyClock::now() - start).count();
  report.sim_seconds = world.clock().seconds();
  report.steps = world.clock().steps();
  report.teleports = teleports.counts();
  if (report.rss_warm_mb > 0) report.rss_growth = report.rss_end_mb / report.rss_warm_mb - 1.0;
  report.state_hash = world.StateHash();
  return report;
}

std::string FormatSummary(const SoakReport& r) {
  std::ostringstream out;
  char line[256];
  std::snprintf(line, sizeof line, "soak %s: %.1f s simulated in %.1f s (%.2f× real time), %lld steps, %lld checks\n",
                r.world.c_str(), r.sim_seconds, r.wall_seconds, r.sim_seconds / std::max(r.wall_seconds, 1e-9),
                static_cast<long long>(r.steps), static_cast<long long>(r.checks));
  out << line;
  std::int64_t all = 0;
  out << "teleports:";
  for (int k = 0; k < kTeleportKinds; ++k) {
    all += r.teleports[k];
    out << (k ? ", " : " ") << r.teleports[k] << " " << ToString(static_cast<TeleportKind>(k));
  }
  out << " (" << all << " in all)\n";
  if (r.finding_count == 0) {
    out << "findings: none\n";
  } else {
    out << "findings: " << r.finding_count << " (";
    bool first = true;
    for (int i = 0; i < static_cast<int>(r.by_issue.size()); ++i) {
      if (r.by_issue[i] == 0) continue;
      out << (first ? "" : ", ") << ToString(static_cast<StateIssue>(i)) << " " << r.by_issue[i];
      first = false;
    }
    out << "); " << r.replaced << " objects put back" << (r.stopped_early ? "; stopped at a non-finite state" : "")
        << "\n";
  }
  if (r.rss_warm_mb > 0) {
    std::snprintf(line, sizeof line,
                  "memory: %.1f MB resident after the %.0f s warm-up, %.1f MB at the end (%+.2f %%, limit %.0f %%), "
                  "peak %.1f MB\n",
                  r.rss_warm_mb, r.warmup_seconds, r.rss_end_mb, 100.0 * r.rss_growth, 100.0 * r.max_rss_growth,
                  r.rss_peak_mb);
  } else {
    std::snprintf(line, sizeof line, "memory: not judged (the run ended before the %.0f s warm-up did)\n",
                  r.warmup_seconds);
  }
  out << line;
  std::snprintf(line, sizeof line, "state hash: %016llx\n", static_cast<unsigned long long>(r.state_hash));
  out << line;
  out << "verdict: " << (r.Pass() ? "pass" : "FAIL");
  if (!r.Pass()) {
    if (r.finding_count) out << " (state-check findings)";
    if (r.rss_growth >= r.max_rss_growth) out << " (memory grew)";
  }
  out << "\n";
  return out.str();
}

}  // namespace ubersim::kernel::soak
