# SPDX-License-Identifier: Apache-2.0
"""The league's realism presets measured through the wire (issue 35, item 4).

For each preset (None, Friendly, RC2021, Realistic) `ubersim run COPY --realism PRESET --local-only`
runs a shipped world with its robots standing still and the ball resting at the centre, and what
a team's software receives is held against the preset's numbers (reference/ssl-protocols.md §6.1):

* noise: the robots' position and heading σ, the ball's position σ and its blob area's σ, within
  15 % (a σ of 0: no spread at all, up to the wire's float resolution);
* drop-outs: missing robot and ball detections per frame (binomial, 4 standard errors); false
  balls per robot and second, each at a dribbler's corner (Poisson, 4 standard deviations);
* stamps and latency: t_sent − t_capture is vision_processing_time; the vision delay (t_sent − the
  true capture) from when a teleported ball first shows; in real time, a teleport seen no earlier
  than the vision delay after it was sent;
* the geometry's derived_camera_world_* moved by camera_position_error along (0.3, 0.7, 0.05),
  and object_position_offset (zero for div-b's camera above the centre, ±offset for div-a's two);
* the ball hidden by a robot between it and the camera (enable_invisible_ball): never seen, and
  seen as often as missing_ball_detections allows with the robot beside it;
* command and response loss: commands that move a robot (their effect seen through vision) and
  RobotFeedback entries that come back.

The figures come from the synchronous mode (the test steps the world: nothing depends on the
machine keeping real time; the frames arrive on the multicast group and are checked against the
synchronous response's copies); only the arrival against the wall clock needs a real-time run,
and there only a lower bound is asserted. measurements: realism_wire.py; the same with more
frames writes docs/validation/realism.md (tools/realism_report.py).
"""
import math
import statistics
import unittest

import realism_wire as rw

STILL_SECONDS = 80.0     # simulated: 6000 frames of the one camera, 960 robot-seconds
OCCLUSION_SECONDS = 5.0  # per placement: 375 frames
RADIO_TRIALS = 60        # 12 robot commands each
DELAY_TRIALS = 8
TWO_CAMERA_SECONDS = 5.0
SIGMA_TOLERANCE = 0.15


def measure(preset, still=STILL_SECONDS, occlusion=OCCLUSION_SECONDS, radio=RADIO_TRIALS, delay=DELAY_TRIALS,
            two_cameras=TWO_CAMERA_SECONDS, arrival_frames=100, teleports=6):
    """Every measurement of one preset: {name: result}."""
    out = {"preset": preset}
    with rw.SyncWorld(preset) as world:
        out["command"] = world.command_line()
        out["geometry"] = rw.geometry_cameras(world)
        error = rw.LEAGUE_PRESETS[preset]["camera_position_error"]
        out["geometry_expected"] = rw.expected_cameras(world.world.data, error)
        out["still"] = rw.measure_still(world, still)
        out["delay"] = rw.measure_delay(world, delay)
        out["occlusion"] = rw.measure_occlusion(world, occlusion)
        out["radio"] = rw.measure_radio(world, radio)
        out["mismatches"] = list(world.mismatches)
        out["requests"] = world.requests
    with rw.SyncWorld(preset, world="div-a") as world:
        out["two_cameras"] = rw.measure_two_cameras(world, two_cameras)
        out["two_cameras_expected"] = rw.expected_cameras(world.world.data, error)
        out["mismatches"] += world.mismatches
    with rw.RealTimeWorld(preset) as world:
        out["arrival"] = rw.measure_arrival(world, arrival_frames, teleports)
    return out


def summary(m):
    """The figures in a few lines (printed with the test's output)."""
    s, r, o = m["still"], m["radio"], m["occlusion"]
    lost = r["commands"] - r["unseen"] - r["arrived"]
    trials = m["arrival"]["trials"]
    return "\n".join([
        "%s: %d frames; robot σ %.3f mm, heading σ %.4f rad, ball σ %.3f mm, area σ %.2f px" % (
            m["preset"], s["frames"], s["robot_sigma"] * 1e3, s["robot_phi_sigma"], s["ball_sigma"] * 1e3,
            s["ball_area_sigma"]),
        "  missing robots %d/%d, balls %d/%d; false balls %d in %.0f robot-s (%d at a dribbler corner)" % (
            s["robot_missing"], s["robot_slots"], s["ball_missing"], s["ball_frames"], s["false_balls"],
            s["robot_seconds"], s["false_balls_at_corner"]),
        "  t_sent - t_capture %.6f..%.6f s; vision delay in [%.4f, %.4f] s; teleport seen after %s ms (lag %s ms)" % (
            s["processing_min"], s["processing_max"], m["delay"][0], m["delay"][1],
            ", ".join("%.1f" % (t["w1_minus_w0"] * 1e3) for t in trials),
            ", ".join("%.1f" % (t["lag"] * 1e3) for t in trials)),
        "  arrival - t_capture median %.2f ms, arrival - t_sent median %.2f ms" % (
            statistics.median(m["arrival"]["arrival_minus_capture"]) * 1e3,
            statistics.median(m["arrival"]["arrival_minus_sent"]) * 1e3),
        "  ball hidden: seen in %d/%d frames; robot aside: %d/%d" % (
            o["hidden"]["with_ball"], o["hidden"]["frames"], o["aside"]["with_ball"], o["aside"]["frames"]),
        "  commands lost %d/%d (%d unseen); feedback %d/%d" % (
            lost, r["commands"] - r["unseen"], r["unseen"], r["feedback_received"], r["feedback_expected"]),
        "  cameras div-b %s, div-a %s; ball per div-a camera %s" % (
            m["geometry"], m["two_cameras"]["cameras"],
            {c: "(%.2f, %.2f) mm" % (v[0] * 1e3, v[1] * 1e3) for c, v in m["two_cameras"]["ball"].items()}),
    ])


class PresetThroughTheWire:
    """The tests of one league preset; a subclass names it (PRESET) and is the TestCase."""

    PRESET = None

    @classmethod
    def setUpClass(cls):
        cls.promised = rw.LEAGUE_PRESETS[cls.PRESET]
        cls.m = measure(cls.PRESET)
        print("\n" + summary(cls.m))

    # -- noise --------------------------------------------------------------------------------

    def assert_sigma(self, measured, promised, what):
        self.assertAlmostEqual(measured / promised, 1.0, delta=SIGMA_TOLERANCE,
                               msg="%s: measured σ %.6g, the preset's %.6g" % (what, measured, promised))

    def test_robot_position_and_heading_noise(self):
        s = self.m["still"]
        self.assertGreater(s["robot_samples"], 50000)
        if self.promised["stddev_robot_p"] == 0:
            # No noise: every report on the robot's own (creeping) line, to float32 mm on the wire.
            self.assertLess(s["robot_largest"], 1e-6)
        else:
            self.assert_sigma(s["robot_sigma"], self.promised["stddev_robot_p"], "robot position")
        if self.promised["stddev_robot_phi"] == 0:
            self.assertLess(s["robot_phi_largest"], 1e-5)
        else:
            self.assert_sigma(s["robot_phi_sigma"], self.promised["stddev_robot_phi"], "robot heading")

    def test_ball_position_noise(self):
        s = self.m["still"]
        self.assertGreater(s["ball_samples"], 5000)
        self.assertEqual(s["ball_double"], 0, "the ball twice in one frame")
        if self.promised["stddev_ball_p"] == 0:
            self.assertEqual(s["ball_spread"], 0.0)
        else:
            self.assert_sigma(s["ball_sigma"], self.promised["stddev_ball_p"], "ball position")

    def test_ball_blob_area_noise(self):
        s = self.m["still"]
        if self.promised["stddev_ball_area"] == 0:
            self.assertEqual(s["ball_area_values"], 1, "a resting ball without area noise has one blob size")
        else:
            self.assert_sigma(s["ball_area_sigma"], self.promised["stddev_ball_area"], "ball blob area")
        # The blob's mean is the ball's disc seen from 6 m with a 390 px focal length.
        self.assertAlmostEqual(s["ball_area_mu"], s["ball_area_expected_mean"], delta=0.6)

    # -- drop-outs and false balls -------------------------------------------------------------

    def assert_rate(self, events, trials, p, what):
        lo, hi = rw.binomial_band(p, trials)
        self.assertTrue(lo * trials <= events <= hi * trials,
                        "%s: %d of %d (%.4f), the preset's %.4f allows %.4f..%.4f" % (
                            what, events, trials, events / trials, p, lo, hi))

    def test_missing_robot_detections(self):
        s = self.m["still"]
        self.assertEqual(s["robots_seen"], s["robots_placed"])
        self.assert_rate(s["robot_missing"], s["robot_slots"], self.promised["missing_robot_detections"],
                         "robot detections missing")

    def test_missing_ball_detections(self):
        s = self.m["still"]
        self.assert_rate(s["ball_missing"], s["ball_frames"], self.promised["missing_ball_detections"],
                         "ball detections missing")

    def test_false_ball_detections_at_the_dribblers(self):
        s = self.m["still"]
        expected = self.promised["dribbler_ball_detections"] * s["robot_seconds"]
        lo, hi = rw.poisson_band(expected)
        self.assertTrue(lo <= s["false_balls"] <= hi,
                        "%d false balls in %.0f robot-seconds (%.4f /s), the preset's %.4f /s allows %.1f..%.1f" % (
                            s["false_balls"], s["robot_seconds"], s["false_balls"] / s["robot_seconds"],
                            self.promised["dribbler_ball_detections"], lo, hi))
        self.assertEqual(s["false_balls_at_corner"], s["false_balls"], "a false ball away from any dribbler corner")

    # -- stamps and latency --------------------------------------------------------------------

    def test_processing_time_stamped(self):
        s = self.m["still"]
        want = self.promised["vision_processing_time"] * 1e-9
        self.assertAlmostEqual(s["processing_min"], want, delta=1e-3)
        self.assertAlmostEqual(s["processing_max"], want, delta=1e-3)

    def test_vision_delay_from_capture_to_sending(self):
        lower, upper = self.m["delay"]
        want = self.promised["vision_delay"] * 1e-9
        self.assertLessEqual(lower, want + 1e-9, self.m["delay"])
        self.assertGreaterEqual(upper, want - 1e-9, self.m["delay"])
        self.assertLessEqual(upper - lower, rw.PHYSICS_STEP + 1e-9, "the bracket is no tighter than a step")

    def test_arrival_in_real_time_no_earlier_than_the_vision_delay(self):
        # A lower bound only: a busy machine makes everything later, and a simulator that ran
        # behind and catches up is allowed for by the lag it had (read from the stamps).
        want = self.promised["vision_delay"] * 1e-9
        for t in self.m["arrival"]["trials"]:
            self.assertGreaterEqual(t["w1_minus_w0"] + t["lag"], want - 0.003, t)

    # -- the cameras ---------------------------------------------------------------------------

    def test_camera_position_error_in_the_geometry(self):
        for got, want in ((self.m["geometry"], self.m["geometry_expected"]),
                          (self.m["two_cameras"]["cameras"], self.m["two_cameras_expected"])):
            self.assertEqual(sorted(got), sorted(want))
            for camera in want:
                for a, b in zip(got[camera], want[camera]):
                    self.assertAlmostEqual(a, b, delta=0.01, msg=(camera, got[camera], want[camera]))

    def test_object_position_offset(self):
        offset = self.promised["object_position_offset"]
        # div-b: its one camera is above the field's centre, so nothing shifts.
        s = self.m["still"]
        for key, (dx, dy) in s["robot_start_offsets"].items():
            self.assertLess(math.hypot(dx, dy), 0.001, key)
        for camera, (dx, dy) in s["ball_mean_offsets"].items():
            self.assertLess(math.hypot(dx, dy), 0.0005, camera)
        # div-a: the ball at the centre, seen by both cameras, each showing it shifted towards itself.
        ball = self.m["two_cameras"]["ball"]
        self.assertEqual(sorted(ball), [0, 1])
        for camera, (dx, dy, n) in ball.items():
            side = math.copysign(1.0, self.m["two_cameras_expected"][camera][0])
            self.assertGreater(n, 300)
            self.assertAlmostEqual(dx, side * offset, delta=0.0005, msg=camera)
            self.assertAlmostEqual(dy, 0.0, delta=0.0005, msg=camera)

    # -- occlusion -----------------------------------------------------------------------------

    def test_ball_hidden_by_a_robot_between_it_and_the_camera(self):
        self.assertTrue(self.promised["enable_invisible_ball"])
        o = self.m["occlusion"]
        hidden, aside = o["hidden"], o["aside"]
        for placement in (hidden, aside):
            self.assertGreater(placement["robot_there"], 0.9 * placement["frames"], "the robot is not where it was put")
        self.assertEqual(hidden["with_ball"], 0, "the ball was seen through the robot")
        self.assert_rate(aside["frames"] - aside["with_ball"], aside["frames"],
                         self.promised["missing_ball_detections"], "ball missing with the robot beside it")

    # -- the radio -----------------------------------------------------------------------------

    def test_command_loss(self):
        r = self.m["radio"]
        seen = r["commands"] - r["unseen"]
        self.assertGreater(seen, 0.95 * r["commands"])
        # A command moved its robot some 2 cm; a lost one left it where it stood: nothing between.
        unclear = [d for d in r["displacements"] if 0.004 < d < 0.015]
        self.assertEqual(unclear, [], "robots that neither stood nor drove")
        self.assert_rate(seen - r["arrived"], seen, self.promised["robot_command_loss"], "commands lost")

    def test_response_loss(self):
        r = self.m["radio"]
        self.assert_rate(r["feedback_expected"] - r["feedback_received"], r["feedback_expected"],
                         self.promised["robot_response_loss"], "RobotFeedback entries lost")

    def test_multicast_frames_are_the_synchronous_responses_frames(self):
        self.assertEqual(self.m["mismatches"], [])


class NonePreset(PresetThroughTheWire, unittest.TestCase):
    PRESET = "None"


class FriendlyPreset(PresetThroughTheWire, unittest.TestCase):
    PRESET = "Friendly"


class RC2021Preset(PresetThroughTheWire, unittest.TestCase):
    PRESET = "RC2021"


class RealisticPreset(PresetThroughTheWire, unittest.TestCase):
    PRESET = "Realistic"


class RealismChangedWhileRunning(unittest.TestCase):
    def test_a_clients_realism_config_turns_none_into_rc2021(self):
        with rw.RealTimeWorld("None") as world:
            m = rw.measure_switch(world)
        print("\nNone -> RC2021 while running: %s" % m)
        before, after = m["before"], m["after"]
        self.assertEqual(m["codes"], [])
        self.assertLess(before["robot_sigma"], 1e-6)
        self.assertEqual(before["ball_sigma"], 0.0)
        self.assertEqual(before["ball_areas"], 1)
        self.assertEqual(before["processing"], [0.005])
        rc2021 = rw.LEAGUE_PRESETS["RC2021"]
        self.assertAlmostEqual(after["robot_sigma"] / rc2021["stddev_robot_p"], 1.0, delta=SIGMA_TOLERANCE)
        self.assertGreater(after["ball_sigma"], 0.0)
        self.assertGreater(after["ball_areas"], 1)
        self.assertEqual(after["processing"], [0.01])


if __name__ == "__main__":
    unittest.main()
