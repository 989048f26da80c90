#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""The league's realism presets measured through the wire, written to docs/validation/realism.md:
per preset (None, Friendly, RC2021, Realistic) what it promises (reference/ssl-protocols.md §6.1)
against what a team's software receives from `ubersim run COPY --realism PRESET --local-only`.
The same measurements as tests/interfaces/test_realism_wire.py (realism_wire.py), with more
frames; the bands are the test's (σ within 15 %, rates within 4 standard errors).

    /usr/bin/python3 tools/realism_report.py            # from the source tree, build/ built
    /usr/bin/python3 tools/realism_report.py --build B --out FILE --still 240 --radio 200

Needs Debian's python3-protobuf and python3-yaml (the interface tests' Python) and the build's
generated *_pb2 modules (BUILD/python). Takes about two minutes; prints each preset as it goes.
Exit code 1 when a figure is outside its band.
"""
import argparse
import datetime
import math
import os
import platform
import shlex
import statistics
import subprocess
import sys
import time

SOURCE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PRESETS = ["None", "Friendly", "RC2021", "Realistic"]


def setup(build):
    os.environ.setdefault("UBERSIM_BINARY", os.path.join(build, "bin", "ubersim"))
    os.environ.setdefault("UBERSIM_SOURCE_DIR", SOURCE)
    sys.path[:0] = [os.path.join(build, "python"), os.path.join(SOURCE, "tests", "interfaces")]


def git(*args):
    try:
        return subprocess.run(["git", "-C", SOURCE, *args], capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return ""


class Table:
    """Rows of (quantity, promised, measured, band, verdict) in Markdown."""

    def __init__(self):
        self.rows = []
        self.failed = 0

    def add(self, quantity, promised, measured, band, ok):
        verdict = "ok" if ok is True else ("—" if ok is None else "**OUT**")
        self.rows.append((quantity, promised, measured, band, verdict))
        self.failed += ok is False

    def markdown(self):
        lines = ["| quantity | promised | measured | band | |", "|---|---|---|---|---|"]
        lines += ["| %s | %s | %s | %s | %s |" % r for r in self.rows]
        return "\n".join(lines)


def sigma_row(table, quantity, unit, scale, measured, promised, zero_measure, zero_limit, zero_text,
              zero_name="largest deviation from its line"):
    """σ within 15 % of the promise; a promise of 0: `zero_measure` (the largest deviation or the
    spread) no more than `zero_limit`."""
    if promised == 0:
        table.add(quantity, "0", "%.3g %s (%s)" % (zero_measure * scale, unit, zero_name), zero_text,
                  zero_measure <= zero_limit)
    else:
        ratio = measured / promised
        table.add(quantity, "%.4g %s" % (promised * scale, unit),
                  "%.4g %s (%+.1f %%)" % (measured * scale, unit, 100 * (ratio - 1)), "± 15 %",
                  abs(ratio - 1) <= 0.15)


def rate_row(rw, table, quantity, events, trials, p):
    lo, hi = rw.binomial_band(p, trials)
    table.add(quantity, "%.4g" % p, "%.4f (%d of %d)" % (events / trials, events, trials),
              "%.4f … %.4f" % (lo, hi), lo * trials <= events <= hi * trials)


def preset_section(m, rw):
    p = rw.LEAGUE_PRESETS[m["preset"]]
    s, r, o, a = m["still"], m["radio"], m["occlusion"], m["arrival"]
    t = Table()
    sigma_row(t, "robot position σ", "mm", 1e3, s["robot_sigma"], p["stddev_robot_p"], s["robot_largest"], 1e-6,
              "< 0.001 mm")
    sigma_row(t, "robot heading σ", "rad", 1, s["robot_phi_sigma"], p["stddev_robot_phi"], s["robot_phi_largest"],
              1e-5, "< 1e-5 rad")
    sigma_row(t, "ball position σ", "mm", 1e3, s["ball_sigma"], p["stddev_ball_p"], s["ball_spread"], 0.0, "0",
              "spread")
    if p["stddev_ball_area"] == 0:
        t.add("ball blob area σ", "0", "%d distinct value(s), %.0f px" % (s["ball_area_values"], s["ball_area_mu"]),
              "1 value", s["ball_area_values"] == 1)
    else:
        ratio = s["ball_area_sigma"] / p["stddev_ball_area"]
        t.add("ball blob area σ", "%.3g px" % p["stddev_ball_area"],
              "%.3g px (%+.1f %%), mean %.2f px" % (s["ball_area_sigma"], 100 * (ratio - 1), s["ball_area_mu"]),
              "± 15 %", abs(ratio - 1) <= 0.15)
    rate_row(rw, t, "missing robot detections / frame", s["robot_missing"], s["robot_slots"],
             p["missing_robot_detections"])
    rate_row(rw, t, "missing ball detections / frame", s["ball_missing"], s["ball_frames"],
             p["missing_ball_detections"])
    expected = p["dribbler_ball_detections"] * s["robot_seconds"]
    lo, hi = rw.poisson_band(expected)
    t.add("false balls / robot / s", "%.3g" % p["dribbler_ball_detections"],
          "%.4f (%d in %.0f robot-s; %d at a dribbler corner)" % (
              s["false_balls"] / s["robot_seconds"], s["false_balls"], s["robot_seconds"], s["false_balls_at_corner"]),
          "%.0f … %.0f balls" % (lo, hi),
          lo <= s["false_balls"] <= hi and s["false_balls_at_corner"] == s["false_balls"])
    want = p["vision_processing_time"] * 1e-9
    t.add("t_sent − t_capture (vision_processing_time)", "%.1f ms" % (want * 1e3),
          "%.4f … %.4f ms" % (s["processing_min"] * 1e3, s["processing_max"] * 1e3), "± 1 ms",
          abs(s["processing_min"] - want) <= 1e-3 and abs(s["processing_max"] - want) <= 1e-3)
    delay = p["vision_delay"] * 1e-9
    lo, hi = m["delay"]
    t.add("vision delay, t_sent − true capture (synchronous)", "%.1f ms" % (delay * 1e3),
          "%.2f … %.2f ms" % (lo * 1e3, hi * 1e3), "contains it", lo <= delay + 1e-9 and hi >= delay - 1e-9)
    e2e = [x["w1_minus_w0"] for x in a["trials"]]
    t.add("teleport → first frame showing it (real time, wall clock)", "≥ %.1f ms" % (delay * 1e3),
          "min %.1f, median %.1f ms (lag ≤ %.1f ms)" % (min(e2e) * 1e3, statistics.median(e2e) * 1e3,
                                                       max(x["lag"] for x in a["trials"]) * 1e3),
          "with the lag ≥ %.0f ms" % (delay * 1e3 - 3),
          all(x["w1_minus_w0"] + x["lag"] >= delay - 0.003 for x in a["trials"]))
    t.add("arrival − t_capture (real time)", "—", "median %.2f ms (arrival − t_sent %.2f ms)" % (
        statistics.median(a["arrival_minus_capture"]) * 1e3, statistics.median(a["arrival_minus_sent"]) * 1e3),
        "—", None)
    h, s2 = o["hidden"], o["aside"]
    t.add("frames with the ball, a robot between it and the camera", "0", "%d of %d" % (h["with_ball"], h["frames"]),
          "0", h["with_ball"] == 0)
    lo, hi = rw.binomial_band(p["missing_ball_detections"], s2["frames"])
    t.add("frames with the ball, the robot beside it", "%.3g" % (1 - p["missing_ball_detections"]),
          "%.4f (%d of %d)" % (s2["with_ball"] / s2["frames"], s2["with_ball"], s2["frames"]),
          "%.4f … %.4f" % (1 - hi, 1 - lo), (1 - hi) * s2["frames"] <= s2["with_ball"] <= (1 - lo) * s2["frames"])
    seen = r["commands"] - r["unseen"]
    rate_row(rw, t, "robot commands lost (robot_command_loss)", seen - r["arrived"], seen, p["robot_command_loss"])
    rate_row(rw, t, "RobotFeedback entries lost (robot_response_loss)", r["feedback_expected"] - r["feedback_received"],
             r["feedback_expected"], p["robot_response_loss"])
    for name, got, want_cams in (("div-b", m["geometry"], m["geometry_expected"]),
                                 ("div-a", m["two_cameras"]["cameras"], m["two_cameras_expected"])):
        same = sorted(got) == sorted(want_cams)
        worst = max(abs(x - y) for c in want_cams for x, y in zip(got[c], want_cams[c])) if same else math.inf
        t.add("derived_camera_world_* (%s), camera_position_error %.3g m" % (name, p["camera_position_error"]),
              "; ".join("(%.1f, %.1f, %.1f)" % w for w in want_cams.values()),
              "; ".join("(%.1f, %.1f, %.1f)" % g for g in got.values()), "± 0.01 mm", worst <= 0.01)
    worst = max(math.hypot(*d) for d in s["robot_start_offsets"].values())
    t.add("object offset, div-b (camera above the centre)", "0", "%.2f mm (largest robot)" % (worst * 1e3), "< 1 mm",
          worst < 0.001)
    ball = m["two_cameras"]["ball"]
    offset = p["object_position_offset"]
    ok = sorted(ball) == [0, 1] and all(
        abs(v[0] - math.copysign(offset, m["two_cameras_expected"][c][0])) <= 0.0005 and abs(v[1]) <= 0.0005
        for c, v in ball.items())
    t.add("object offset, div-a, the centre ball per camera (x)", "∓%.0f mm" % (offset * 1e3),
          ", ".join("camera %d %+.2f mm" % (c, v[0] * 1e3) for c, v in sorted(ball.items())), "± 0.5 mm", ok)
    t.add("multicast frames = the synchronous response's frames", "—", "%d differ" % len(m["mismatches"]), "0",
          not m["mismatches"])
    text = "## %s\n\n`%s` (ball at the centre, robots where the world file puts them; %d frames of one camera, " \
           "%.0f s of simulated time, for the noise and drop-outs; %d radio trials of 12 robots)\n\n%s\n" % (
               m["preset"], m["command"], s["frames"], s["seconds"], r["commands"] // 12, t.markdown())
    return text, t.failed


def switch_section(m):
    b, a = m["before"], m["after"]
    return ("## A client's realism config while running: None → RC2021\n\n"
            "`ubersim run <copy of div-b> --realism None --local-only` in real time; a `RealismConfigErForce` "
            "with every RC2021 field sent to the control port (answer: %s).\n\n"
            "| | robot position σ | ball position σ | ball blob areas | t_sent − t_capture |\n"
            "|---|---|---|---|---|\n"
            "| before | %.3g mm | %.3g mm | %d value(s) | %s ms |\n"
            "| after | %.3f mm | %.3f mm | %d values | %s ms |\n") % (
        "no errors" if not m["codes"] else ", ".join(m["codes"]),
        b["robot_sigma"] * 1e3, b["ball_sigma"] * 1e3, b["ball_areas"], ms(b["processing"]),
        a["robot_sigma"] * 1e3, a["ball_sigma"] * 1e3, a["ball_areas"], ms(a["processing"]))


def ms(seconds):
    return ", ".join("%g" % (x * 1e3) for x in seconds)


NOTES = """## How it is measured

* **The world.** A copy of the shipped `models/worlds/div-b.yaml` (one camera 6 m above the centre, 75 Hz, 12
  robots) with the `ssl_vision` and `ssl_simulation` transports on free ports, run as
  `ubersim run COPY --realism PRESET --local-only`. Its perception preset, ÜberSim's `realistic`, adds four
  effects the league's presets have no field for and so leave on (noise growing 10 %%/m away from the nadir,
  capture jitter, motion smear, unsynchronised cameras); the copy switches them off
  (`noise.growth_per_metre: 0`, `capture_jitter: 0`, `exposure: 0`, `unsynchronised_cameras: false`) so that
  the figures are the league preset's alone. The physics step (5 ms, the `fast` profile) is written out.
  The two-camera figures use `div-a` the same way.
* **Synchronous mode.** The test steps the world (`SimulationSyncRequest`), so nothing depends on the
  machine keeping real time, and each frame's simulated send time is known. Every frame is read from the
  vision multicast group (joined on loopback: `--local-only` sends there) and checked against the
  synchronous response's copy.
* **Noise.** σ is the scatter about each robot's (and the ball's) own least-squares line in time, pooled over
  x and y: a standing robot creeps by itself (see below), which a line takes out and white noise does not
  notice. The blob area is reported as `round(max(0, μ + noise))`; with 6.5 px of noise on a 6 px blob many
  reports are 0, so σ is the maximum-likelihood fit of that censored, rounded normal, not the plain
  standard deviation.
* **Rates** are judged by 4 standard errors of a binomial (drop-outs, losses) or 4 √λ of a Poisson count
  (false balls), with the preset's own rate.
* **Vision delay** (t_sent − the true capture): the ball teleported at a known simulated time; the last frame
  still showing the old spot and the first showing the new one bound the delay, and trials at other phases of
  the camera's period narrow it to the step.
* **Real time.** `t_capture` is stamped `t_sent − vision_processing_time`, as ER-Force's simulator does, so
  *arrival − t_capture* is the processing time plus the transport, not the vision delay; the true delay
  shows in how long a teleport takes to be seen (command sent → first frame showing it arrives), which is at
  least `vision_delay` while the simulator keeps time (the lag it had, read from the stamps, is added).
* **Occlusion.** The ball 3 m from the nadir, a robot 1 cm in front of it on the line to the nadir (its back to
  the ball): fully hidden. Then the robot 0.5 m to the side.
* **Command loss.** Each trial puts the 12 robots back where the world file has them (at rest) and gives
  each one command, forward at 1 m/s (blue in the synchronous request, yellow on its UDP port); a robot
  that moved more than 1 cm after 0.3 s got it (those that did get it move about 2 cm; those that did not
  stay within the noise). The responses' `RobotFeedback` entries count the lost feedback.
* **Seeded.** Every run draws from the world's `seed` (1), so the synchronous measurements repeat exactly;
  RC2021 and Realistic, with the same loss probabilities, lose the same commands and the same feedback.

## Seen along the way

* **Standing robots creep.** A robot without commands on the shipped robot model moves by itself, steadily:
  %(creep)s. It shows as a growing offset, not as
  noise, and the line fits above take it out.
* **The wire clock runs a little ahead.** `t_sent` is stamped a few milliseconds later than the datagram
  actually leaves: in the real-time runs arrival − t_sent is %(ahead)s (median), where a real camera's
  packets arrive after their t_sent. The offset is the same all through a run, so it is set when the stamps
  are anchored: most likely the first step's own work, as the stamps are anchored when that step is
  published while the steps are paced from the moment it began.
"""


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--build", default=os.path.join(SOURCE, "build"), help="the build tree (default: ./build)")
    parser.add_argument("--out", default=os.path.join(SOURCE, "docs", "validation", "realism.md"))
    parser.add_argument("--still", type=float, default=240.0, help="simulated seconds of the still scene per preset")
    parser.add_argument("--radio", type=int, default=200, help="command-loss trials (12 robots each) per preset")
    parser.add_argument("--occlusion", type=float, default=20.0, help="simulated seconds per occlusion placement")
    parser.add_argument("--presets", nargs="*", default=PRESETS)
    args = parser.parse_args()
    setup(os.path.abspath(args.build))
    import realism_wire as rw
    import test_realism_wire as t

    started = time.monotonic()
    sections, failed, creeps, ahead = [], 0, [], []
    for preset in args.presets:
        m = t.measure(preset, still=args.still, occlusion=args.occlusion, radio=args.radio, delay=16,
                      two_cameras=20.0, arrival_frames=300, teleports=10)
        print(t.summary(m), flush=True)
        text, bad = preset_section(m, rw)
        sections.append(text)
        failed += bad
        creeps.append(m["still"]["robot_creep"])
        ahead.append(statistics.median(m["arrival"]["arrival_minus_sent"]))
    with rw.RealTimeWorld("None") as world:
        switch = rw.measure_switch(world, frames=300)
    elapsed = time.monotonic() - started

    commit = git("rev-parse", "--short", "HEAD")
    dirty = " (with uncommitted changes)" if git("status", "--porcelain") else ""
    header = ("# The league's realism presets, measured through the wire\n\n"
              "Written by `%s`; the test suite (`tests/interfaces/test_realism_wire.py`) makes the "
              "same measurements with fewer frames and asserts the same bands. Promised: ER-Force's "
              "`config/simulator-realism/*.txt`, every `RealismConfigErForce` field "
              "(`../shared/reference/ssl-protocols.md` §6.1; the presets side by side in "
              "[interfaces.md](../interfaces.md#realism-presets-side-by-side)). "
              "Measured: what a team's software receives — the SSL-Vision multicast, the simulation protocol's "
              "responses.\n\n"
              "%s UTC, commit %s%s, %s, %d cores; %.0f s.\n\n**%s**\n") % (
        shlex.join(["tools/realism_report.py"] + sys.argv[1:]),
        datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M"), commit or "unknown", dirty,
        platform.system(), os.cpu_count() or 0, elapsed,
        "Every figure within its band." if not failed else "%d figure(s) outside their band." % failed)
    creep = "up to %.2f mm/s (%.0f mm a minute) in the `fast` profile's 5 ms steps, backwards along its heading" % (
        max(creeps) * 1e3, max(creeps) * 60e3)
    notes = NOTES % {"creep": creep, "ahead": "%+.1f ms" % (statistics.median(ahead) * 1e3)}
    with open(args.out, "w", encoding="utf-8") as f:
        f.write(header + "\n" + "\n".join(sections) + "\n" + switch_section(switch) + "\n" + notes)
    print("wrote %s in %.0f s; %d figure(s) outside their band" % (args.out, elapsed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
