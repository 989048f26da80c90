# SPDX-License-Identifier: Apache-2.0
"""The shipped world as the league's simulated-match setup runs a simulator: `ubersim run
models/worlds/div-b.yaml` with the command line ER-Force's simulator-cli takes (--realism, -g,
the ports), and the SimulatorCommands ssl-simulation-controller sends (robots on and off the field,
robot_specs with ER-Force's custom spec under a bare type URL, a client clearing ids 0..15).

Loopback only (--local-only): a test outside a network namespace of its own never opens the LAN.
"""
import json
import math
import os
import statistics
import time
import unittest
import urllib.request

import harness
import ssl_gc_common_pb2 as common_pb
import ssl_simulation_control_pb2 as control_pb
import ssl_simulation_custom_erforce_pb2 as erforce_pb
import ssl_simulation_robot_control_pb2 as robot_pb
import ssl_simulation_robot_feedback_pb2 as feedback_pb
import ssl_vision_wrapper_pb2 as wrapper_pb

SHIPPED_WORLD = os.path.join(harness.MODELS_DIR, "worlds", "div-b.yaml")


def parse(data):
    packet = wrapper_pb.SSL_WrapperPacket()
    packet.ParseFromString(data)
    return packet


class Shipped:
    """`ubersim run` on the shipped Div B world with its ports moved to free ones by flags."""

    def __init__(self, *more):
        (self.vision, self.control, self.blue, self.yellow, self.grsim, self.viewer) = harness.free_udp_ports(6)
        args = ["--vision-port", self.vision, "--control-port", self.control, "--blue-port", self.blue,
                "--yellow-port", self.yellow, "--grsim-port", self.grsim, "--viewer-port", self.viewer, *more]
        self.receiver = harness.MulticastReceiver(self.vision)
        self.sim = harness.Simulator(SHIPPED_WORLD, extra_args=[str(a) for a in args]).start()
        self.client = harness.UdpClient()
        self.receiver.recv_until(lambda p: p.HasField("detection"), 30.0, parse)  # up and running

    def command(self, cmd):
        """Sends a SimulatorCommand; the SimulatorResponse's error codes."""
        while self.client.recv(0.001):  # answers to robot commands sent from this socket
            pass
        self.client.send(cmd, self.control)
        reply = self.client.recv(10.0)
        assert reply is not None, "no SimulatorResponse:\n" + self.sim.output()
        response = control_pb.SimulatorResponse()
        response.ParseFromString(reply[0])
        return [e.code for e in response.errors], response

    def detections(self, count, timeout=30.0):
        """The next `count` detection frames."""
        items = self.receiver.collect_until(lambda got: sum(p.HasField("detection") for _, p in got) >= count,
                                            timeout, parse)
        return [p.detection for _, p in items if p.HasField("detection")]

    def robots(self, detection):
        """{(team, id): (x, y)} in mm."""
        out = {("blue", r.robot_id): (r.x, r.y) for r in detection.robots_blue}
        out.update({("yellow", r.robot_id): (r.x, r.y) for r in detection.robots_yellow})
        return out

    def close(self):
        self.client.close()
        self.sim.close()
        self.receiver.close()


def teleport(cmd, team, rid, x=None, y=None, present=None):
    t = cmd.control.teleport_robot.add()
    t.id.id = rid
    t.id.team = team
    if x is not None:
        t.x, t.y = x, y
    if present is not None:
        t.present = present
    return t


class TwoSimulators(unittest.TestCase):
    def test_two_runs_with_different_ports_do_not_disturb_each_other(self):
        a, b = Shipped(), Shipped()
        self.addCleanup(a.close)
        self.addCleanup(b.close)
        for s in (a, b):
            s.detections(5)
        cmd = control_pb.SimulatorCommand()
        cmd.control.teleport_ball.x = 1.0
        cmd.control.teleport_ball.y = 0.5
        self.assertEqual(a.command(cmd)[0], [])
        a.receiver.drain()
        b.receiver.drain()
        self.assertTrue(any(abs(ball.x - 1000) < 30 and abs(ball.y - 500) < 30
                            for d in a.detections(20) for ball in d.balls))
        self.assertTrue(all(abs(ball.x) < 30 and abs(ball.y) < 30 for d in b.detections(20) for ball in d.balls))


class VisionPort(unittest.TestCase):
    def test_a_clients_vision_port_moves_the_packets_there(self):
        s = Shipped()
        self.addCleanup(s.close)
        (other,) = harness.free_udp_ports(1)
        with harness.MulticastReceiver(other) as moved:
            cmd = control_pb.SimulatorCommand()
            cmd.config.vision_port = other
            self.assertEqual(s.command(cmd)[0], [])
            moved.recv_until(lambda p: p.HasField("geometry"), 10.0, parse)  # the geometry at once
            moved.recv_until(lambda p: p.HasField("detection"), 10.0, parse)
            time.sleep(0.1)
            s.receiver.drain()
            self.assertIsNone(s.receiver.recv(0.5), "still sending to the old port")
        cmd = control_pb.SimulatorCommand()
        cmd.config.vision_port = 0
        self.assertEqual(s.command(cmd)[0], ["UBERSIM_INVALID_VALUE"])


class Realism(unittest.TestCase):
    def test_rc2021_gives_the_presets_noise_latency_and_losses_through_the_wire(self):
        s = Shipped("--realism", "RC2021")
        self.addCleanup(s.close)
        frames = s.detections(200)
        # The frames leave 35 ms (vision_delay) after the capture, stamped with RC2021's 10 ms
        # vision_processing_time as t_sent - t_capture, as ER-Force's simulator stamps them.
        stamped = [d.t_sent - d.t_capture for d in frames]
        self.assertAlmostEqual(statistics.median(stamped), 0.010, delta=0.002)
        # A robot standing still: its reported x scatters with RC2021's σ of 1.3 mm.
        xs = [r.x for d in frames for r in d.robots_yellow if r.robot_id == 3]
        self.assertGreater(len(xs), 100)
        self.assertGreater(statistics.stdev(xs), 0.9)
        self.assertLess(statistics.stdev(xs), 1.8)
        # The ball's blob area is reported, with RC2021's 6.5 px of noise on it.
        areas = [b.area for d in frames for b in d.balls if abs(b.x) < 100 and abs(b.y) < 100]
        self.assertGreater(len(areas), 100)
        self.assertTrue(all(b.HasField("area") for d in frames for b in d.balls))
        self.assertGreater(statistics.pstdev(areas), 2.0, areas[:20])
        # Every field of the preset is modelled: nothing is listed as left out.
        out = s.sim.output()
        self.assertNotIn("not modelled", out)
        self.assertNotIn("left out", out)
        # RC2021's robot_response_loss 0.1: about one robot's answer in ten is left out.
        rc = robot_pb.RobotControl()
        for rid in range(6):
            rc.robot_commands.add(id=rid, dribbler_speed=0.0)
        answered = commanded = 0
        with harness.UdpClient() as team:
            for _ in range(100):
                team.send(rc, s.yellow)
                reply = team.recv(10.0)
                self.assertIsNotNone(reply)
                response = feedback_pb.RobotControlResponse()
                response.ParseFromString(reply[0])
                self.assertEqual([e.code for e in response.errors], [])
                commanded += len(rc.robot_commands)
                answered += len(response.feedback)
                time.sleep(0.005)  # a few steps apart: each step draws its losses anew
        lost = 1.0 - answered / commanded
        self.assertGreater(lost, 0.03, (answered, commanded))
        self.assertLess(lost, 0.2, (answered, commanded))

    def test_none_has_no_noise(self):
        s = Shipped("--realism", "None")
        self.addCleanup(s.close)
        xs = [r.x for d in s.detections(100) for r in d.robots_yellow if r.robot_id == 3]
        self.assertLess(statistics.pstdev(xs), 0.3)  # what remains is the robot settling, not noise


class RobotsAsInAMatch(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.s = Shipped("--realism", "None", "-g", "div-b")

    @classmethod
    def tearDownClass(cls):
        cls.s.close()

    def visible(self):
        return set(self.s.robots(self.s.detections(3)[-1]))

    def settle(self):
        """Frames in flight (35 ms) are out: the next frames show what is now."""
        time.sleep(0.1)
        self.s.receiver.drain()

    def test_a_client_clearing_ids_0_to_15_moves_the_twelve_robots_and_nothing_else(self):
        cmd = control_pb.SimulatorCommand()
        for team, x in ((common_pb.BLUE, -4.0), (common_pb.YELLOW, 4.0)):
            for rid in range(16):
                teleport(cmd, team, rid, x, -2.5 + 0.33 * rid)
        self.assertEqual(self.s.command(cmd)[0], [])
        self.settle()
        seen = self.s.robots(self.s.detections(3)[-1])
        self.assertEqual(len(seen), 12)
        for (team, rid), (x, _) in seen.items():
            self.assertAlmostEqual(abs(x), 4000, delta=60, msg=(team, rid))

    def test_a_clients_camera_position_error_moves_the_cameras_the_geometry_reports(self):
        def realism(**fields):
            cmd = control_pb.SimulatorCommand()
            cmd.config.realism_config.custom.add().Pack(erforce_pb.RealismConfigErForce(**fields))
            return cmd

        def cameras(packet):
            return {c.camera_id: (c.derived_camera_world_tx, c.derived_camera_world_ty, c.derived_camera_world_tz)
                    for c in packet.geometry.calib}

        true = cameras(self.s.receiver.recv_until(lambda p: p.HasField("geometry"), 10.0, parse))
        self.assertTrue(true)
        self.addCleanup(lambda: self.s.command(realism(camera_position_error=0.0)))
        self.assertEqual(self.s.command(realism(camera_position_error=0.1))[0], [])
        # The geometry goes out again at once, each camera 100 mm off along (0.3, 0.7, 0.05).
        norm = math.sqrt(0.3 ** 2 + 0.7 ** 2 + 0.05 ** 2)
        want = {i: (x + 100 * 0.3 / norm, y + 100 * 0.7 / norm, z + 100 * 0.05 / norm) for i, (x, y, z) in true.items()}

        def moved(packet):
            got = cameras(packet) if packet.HasField("geometry") else {}
            return got.keys() == want.keys() and all(
                abs(a - b) < 0.5 for i in got for a, b in zip(got[i], want[i]))

        self.s.receiver.recv_until(moved, 10.0, parse)

    def feedback(self, rid):
        """A RobotControl for yellow `rid` (a dribbler command): (error codes, ids with feedback)."""
        rc = robot_pb.RobotControl()
        rc.robot_commands.add(id=rid, dribbler_speed=0.0)
        with harness.UdpClient() as team:
            team.send(rc, self.s.yellow)
            reply = team.recv(10.0)
        self.assertIsNotNone(reply)
        response = feedback_pb.RobotControlResponse()
        response.ParseFromString(reply[0])
        return [e.code for e in response.errors], [f.id for f in response.feedback]

    def viewer_robots(self):
        with urllib.request.urlopen(f"http://127.0.0.1:{self.s.viewer}/api/state", timeout=10) as r:
            state = json.loads(r.read())
        return {(r["team"], r["id"]) for r in state["robots"] if r.get("present", True)}

    def test_robots_come_on_go_off_and_come_back(self):
        cmd = control_pb.SimulatorCommand()
        teleport(cmd, common_pb.YELLOW, 9, 1.0, 1.0, present=True)
        self.assertEqual(self.s.command(cmd)[0], [])
        self.settle()
        self.assertIn(("yellow", 9), self.visible())
        self.assertEqual(self.feedback(9), ([], [9]))
        harness.wait_for(lambda: ("yellow", 9) in self.viewer_robots(), 10, what="yellow 9 in the viewer")
        cmd = control_pb.SimulatorCommand()
        teleport(cmd, common_pb.YELLOW, 9, present=False)
        self.assertEqual(self.s.command(cmd)[0], [])
        self.settle()
        self.assertNotIn(("yellow", 9), self.visible())
        self.assertEqual(self.feedback(9), (["UBERSIM_UNKNOWN_ROBOT"], []))
        harness.wait_for(lambda: ("yellow", 9) not in self.viewer_robots(), 10, what="yellow 9 gone from the viewer")
        cmd = control_pb.SimulatorCommand()
        teleport(cmd, common_pb.YELLOW, 9, -1.0, 1.0, present=True)
        self.assertEqual(self.s.command(cmd)[0], [])
        self.settle()
        self.assertIn(("yellow", 9), self.visible())
        # Without a place it cannot come on; with an id of 16 it is no robot at all.
        cmd = control_pb.SimulatorCommand()
        teleport(cmd, common_pb.BLUE, 12, present=True)
        teleport(cmd, common_pb.BLUE, 16, 0.0, 0.0, present=True)
        self.assertEqual(sorted(self.s.command(cmd)[0]), ["UBERSIM_CREATE_NO_POSITION", "UBERSIM_INVALID_ROBOT_ID"])

    def test_robot_specs_change_the_radius_and_top_speed_seen_through_vision(self):
        cmd = control_pb.SimulatorCommand()
        spec = cmd.config.robot_specs.add()
        spec.id.id = 1
        spec.id.team = common_pb.BLUE
        spec.radius = 0.095
        spec.limits.vel_absolute_max = 1.0
        custom = erforce_pb.RobotSpecErForce(shoot_radius=0.09, dribbler_width=0.07)
        spec.custom.add(type_url="RobotSpecErForce", value=custom.SerializeToString())  # bare, as the controller sends it
        codes, _ = self.s.command(cmd)
        self.assertEqual(codes, [])
        # The geometry goes out again at once with the new largest radius.
        self.s.receiver.recv_until(lambda p: p.HasField("geometry") and abs(p.geometry.field.max_robot_radius - 95) < 0.01,
                                   10.0, parse)
        # Put both robots apart with room ahead, then drive them at 3 m/s: the spec'd one tops out at 1.
        place = control_pb.SimulatorCommand()
        teleport(place, common_pb.BLUE, 1, -3.0, -2.0).orientation = 0.0
        teleport(place, common_pb.BLUE, 3, -3.0, 2.0).orientation = 0.0
        self.assertEqual(self.s.command(place)[0], [])
        rc = robot_pb.RobotControl()
        for rid in (1, 3):
            c = rc.robot_commands.add(id=rid)
            c.move_command.local_velocity.forward = 3.0
            c.move_command.local_velocity.left = 0.0
            c.move_command.local_velocity.angular = 0.0
        track = {1: [], 3: []}
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline and len(track[1]) < 100:
            self.s.client.send(rc, self.s.blue)
            data = self.s.receiver.recv(0.02)
            if data is None:
                continue
            p = parse(data)
            if p.HasField("detection"):
                for r in p.detection.robots_blue:
                    if r.robot_id in track:
                        track[r.robot_id].append((p.detection.t_capture, r.x, r.y))
        speeds = {}
        for rid, points in track.items():
            (t0, x0, _), (t1, x1, _) = points[-30], points[-1]
            speeds[rid] = (x1 - x0) / 1000.0 / (t1 - t0)
        self.assertLess(speeds[1], 1.05, speeds)
        self.assertGreater(speeds[1], 0.9, speeds)
        self.assertGreater(speeds[3], 2.0, speeds)

    def test_an_impossible_spec_is_answered_per_field(self):
        cmd = control_pb.SimulatorCommand()
        spec = cmd.config.robot_specs.add()
        spec.id.id = 2
        spec.id.team = common_pb.YELLOW
        spec.mass = -2.0
        spec.limits.vel_absolute_max = 400.0
        codes, response = self.s.command(cmd)
        self.assertEqual(codes, ["UBERSIM_INVALID_SPEC", "UBERSIM_INVALID_SPEC"])
        messages = " | ".join(e.message for e in response.errors)
        self.assertIn("body.mass", messages)
        self.assertIn("drive.limits.max_speed", messages)


if __name__ == "__main__":
    unittest.main()
