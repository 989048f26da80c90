# SPDX-License-Identifier: Apache-2.0
"""A shipped world on a machine shaped like a team laptop (a network namespace of the test's own:
loopback without the MULTICAST flag, a LAN interface with the default route; netns.py), run as a
user runs it: `ubersim run models/worlds/div-b.yaml`, no setting changed.

- Every local receiver gets every vision frame once, whether it joins on INADDR_ANY (as most team
  software, grSim's and SSL-Vision's clients do), on 127.0.0.1 or on the LAN address, alone or all
  at once.
- A tool that answers to the vision packets' source address (as ssl-simulation-controller does,
  on port 10300) is heard.
- With no default route, vision still reaches a receiver on loopback, and `ubersim run` says once
  how to make it reach the league's Go tools (loopback's MULTICAST flag).
"""
import os
import time
import unittest

import harness
import netns
import ssl_gc_common_pb2 as common_pb
import ssl_simulation_control_pb2 as control_pb
import ssl_simulation_custom_erforce_pb2 as erforce_pb
import ssl_vision_wrapper_pb2 as wrapper_pb

SHIPPED_WORLD = os.path.join(harness.MODELS_DIR, "worlds", "div-b.yaml")
VISION_PORT = 10020   # the shipped world's
CONTROL_PORT = 10300
FRAME_RATE = 75.0     # div-b's perception preset: realistic


def setUpModule():
    reason = netns.enter()
    if reason:
        raise unittest.SkipTest(reason)


def frames_by_socket(receivers, duration):
    """Detection frames each receiver got during `duration` s, as lists of (camera, frame number)
    in arrival order, and the sources they came from."""
    got = {name: [] for name in receivers}
    sources = {name: set() for name in receivers}
    deadline = time.monotonic() + duration
    while time.monotonic() < deadline:
        for name, r in receivers.items():
            while True:
                received = r.recv_from(0.002)
                if received is None:
                    break
                data, source = received
                packet = wrapper_pb.SSL_WrapperPacket()
                packet.ParseFromString(data)
                sources[name].add(source[0])
                if packet.HasField("detection"):
                    got[name].append((packet.detection.camera_id, packet.detection.frame_number))
    return got, sources


class EveryLocalReceiver(unittest.TestCase):
    """The shipped world, its default settings, three kinds of receiver."""

    @classmethod
    def setUpClass(cls):
        cls.sim = harness.Simulator(SHIPPED_WORLD, extra_args=["--no-viewer"], local_only=False).start()

    @classmethod
    def tearDownClass(cls):
        cls.sim.close()

    def receivers(self, joins):
        out = {}
        for name, interface in joins.items():
            out[name] = harness.MulticastReceiver(VISION_PORT, interface=interface, bind_any=True)
            self.addCleanup(out[name].close)
        return out

    def check_every_frame_once(self, got):
        everything = {f for frames in got.values() for f in frames}
        numbers = sorted(n for _, n in everything)
        self.assertGreater(len(numbers), 50, f"too few frames at all: {got}")
        span = numbers[-1] - numbers[0] + 1
        for name, frames in got.items():
            self.assertEqual(len(frames), len(set(frames)),
                             f"{name}: {len(frames) - len(set(frames))} duplicate frames")
            self.assertGreaterEqual(len(set(frames)), 0.95 * span,
                                    f"{name}: {len(set(frames))} of {span} frames")
        return span

    def test_a_lone_receiver_on_each_interface_gets_every_frame_once(self):
        self.sim.assert_running()
        for name, interface in [("INADDR_ANY", "0.0.0.0"), ("loopback", harness.LOOPBACK),
                                ("LAN address", netns.LAN_ADDRESS)]:
            with self.subTest(name):
                receivers = self.receivers({name: interface})
                harness.wait_for(lambda: receivers[name].recv(0.5), 20, what=f"vision on {name}")
                got, _ = frames_by_socket(receivers, 1.5)
                self.check_every_frame_once(got)
                receivers[name].close()

    def test_all_kinds_at_once_each_get_every_frame_once_at_the_worlds_rate(self):
        self.sim.assert_running()
        receivers = self.receivers({"INADDR_ANY": "0.0.0.0", "loopback": harness.LOOPBACK,
                                    "LAN address": netns.LAN_ADDRESS})
        for r in receivers.values():
            harness.wait_for(lambda: r.recv(0.5), 20, what="vision")
        time.sleep(0.5)  # the sender reads who joined where every 100 ms
        for r in receivers.values():
            r.drain()
        started = time.monotonic()
        got, _ = frames_by_socket(receivers, 3.0)
        span = self.check_every_frame_once(got)
        # One camera at 75 Hz; a starved machine runs the world slower than real time, never faster.
        rate = span / (time.monotonic() - started)
        self.assertLess(rate, 1.1 * FRAME_RATE, f"{rate:.1f} frames/s")
        self.assertGreater(rate, 0.3 * FRAME_RATE, f"{rate:.1f} frames/s")

    def test_a_tool_answering_to_the_vision_source_is_heard(self):
        # ssl-simulation-controller's part: it joins on every multicast interface (here the LAN
        # one), reads the source address of a vision packet and sends SimulatorCommand there.
        self.sim.assert_running()
        receiver = self.receivers({"controller": netns.LAN_ADDRESS})["controller"]
        received = harness.wait_for(lambda: receiver.recv_from(0.5), 20, what="vision")
        source = received[1][0]
        self.assertEqual(source, netns.LAN_ADDRESS, "vision leaves from the LAN address while the LAN has a member")
        command = control_pb.SimulatorCommand()
        command.control.teleport_ball.x = 1.25
        command.control.teleport_ball.y = -0.75
        with harness.UdpClient(host=netns.LAN_ADDRESS) as client:
            client.send(command, CONTROL_PORT, host=source)
            reply = client.recv(5.0)
            self.assertIsNotNone(reply, f"no SimulatorResponse from {source}:{CONTROL_PORT}")
            response = control_pb.SimulatorResponse()
            response.ParseFromString(reply[0])
            self.assertEqual(len(response.errors), 0, response)
            self.assertEqual(reply[1], (source, CONTROL_PORT), "the answer comes from where it was sent")

        def ball_moved():
            data = receiver.recv(0.5)
            if data is None:
                return False
            packet = wrapper_pb.SSL_WrapperPacket()
            packet.ParseFromString(data)
            return any(abs(b.x - 1250) < 30 and abs(b.y + 750) < 30 for b in packet.detection.balls)

        harness.wait_for(ball_moved, 10, what="the teleported ball in vision")

    def test_the_simulation_controllers_commands_take_effect_in_vision(self):
        # What ssl-simulation-controller sends, to the vision's source address: robots on and off
        # the field, and each team's robot_specs with ER-Force's spec under a bare type URL.
        self.sim.assert_running()
        receiver = self.receivers({"controller": netns.LAN_ADDRESS})["controller"]
        source = harness.wait_for(lambda: receiver.recv_from(0.5), 20, what="vision")[1][0]

        def send(cmd):
            with harness.UdpClient(host=netns.LAN_ADDRESS) as client:
                client.send(cmd, CONTROL_PORT, host=source)
                reply = client.recv(5.0)
                self.assertIsNotNone(reply)
                response = control_pb.SimulatorResponse()
                response.ParseFromString(reply[0])
                return [e.code for e in response.errors]

        def seen(team_field, rid, where=None):
            def check():
                data = receiver.recv(0.5)
                if data is None:
                    return False
                packet = wrapper_pb.SSL_WrapperPacket()
                packet.ParseFromString(data)
                if not packet.HasField("detection"):
                    return False
                robots = [r for r in getattr(packet.detection, team_field) if r.robot_id == rid]
                if where is None:
                    return not robots
                return any(abs(r.x - where[0]) < 50 and abs(r.y - where[1]) < 50 for r in robots)
            return check

        cmd = control_pb.SimulatorCommand()
        t = cmd.control.teleport_robot.add(x=1.5, y=-1.5, present=True)
        t.id.id, t.id.team = 8, common_pb.YELLOW
        spec = cmd.config.robot_specs.add(radius=0.09, mass=2.4)
        spec.id.id, spec.id.team = 8, common_pb.YELLOW
        spec.limits.vel_absolute_max = 2.0
        spec.custom.add(type_url="RobotSpecErForce",
                        value=erforce_pb.RobotSpecErForce(shoot_radius=0.085, dribbler_width=0.068).SerializeToString())
        self.assertEqual(send(cmd), [])
        harness.wait_for(seen("robots_yellow", 8, (1500, -1500)), 10, what="yellow 8 on the field")
        cmd = control_pb.SimulatorCommand()
        t = cmd.control.teleport_robot.add(present=False)
        t.id.id, t.id.team = 8, common_pb.YELLOW
        self.assertEqual(send(cmd), [])
        harness.wait_for(seen("robots_yellow", 8), 10, what="yellow 8 off the field")

    def test_run_prints_the_interfaces_it_sends_on(self):
        harness.wait_for(lambda: "publishing ssl_vision" in self.sim.output(), 20, what="the start lines")
        line = next(l for l in self.sim.output().splitlines() if "publishing ssl_vision" in l)
        self.assertIn("lo 127.0.0.1", line)
        self.assertIn(f"{netns.LAN_INTERFACE} {netns.LAN_ADDRESS}", line)
        simulation = next(l for l in self.sim.output().splitlines() if "publishing ssl_simulation" in l)
        self.assertIn(netns.LAN_ADDRESS, simulation)


class NoDefaultRoute(unittest.TestCase):
    """A laptop with no network: loopback only, without its MULTICAST flag."""

    def test_vision_reaches_loopback_and_the_missing_flag_is_named_once(self):
        netns.remove_default_route()
        self.addCleanup(lambda: netns._ip("route", "add", "default", "via", netns.LAN_GATEWAY,
                                          "dev", netns.LAN_INTERFACE))
        with harness.MulticastReceiver(VISION_PORT, interface=harness.LOOPBACK, bind_any=True) as r, \
                harness.Simulator(SHIPPED_WORLD, extra_args=["--no-viewer"], local_only=False) as sim:
            harness.wait_for(lambda: r.recv(0.5), 30, what="vision on loopback")
            got, sources = frames_by_socket({"loopback": r}, 1.5)
            self.assertGreater(len(got["loopback"]), 50)
            self.assertEqual(len(got["loopback"]), len(set(got["loopback"])))
            self.assertEqual(sources["loopback"], {harness.LOOPBACK})
            out = sim.output()
            self.assertEqual(out.count("loopback has no MULTICAST flag"), 1, out)
            self.assertIn("ip link set lo multicast on", out)

    def test_no_warning_once_loopback_has_the_flag(self):
        netns.remove_default_route()
        netns.set_loopback_multicast(True)
        self.addCleanup(netns.set_loopback_multicast, False)
        self.addCleanup(lambda: netns._ip("route", "add", "default", "via", netns.LAN_GATEWAY,
                                          "dev", netns.LAN_INTERFACE))
        with harness.MulticastReceiver(VISION_PORT, interface=harness.LOOPBACK, bind_any=True) as r, \
                harness.Simulator(SHIPPED_WORLD, extra_args=["--no-viewer"], local_only=False) as sim:
            harness.wait_for(lambda: r.recv(0.5), 30, what="vision on loopback")
            self.assertNotIn("MULTICAST flag", sim.output())


class LocalOnly(unittest.TestCase):
    """--local-only: nothing leaves loopback, even with a LAN and a receiver on it."""

    def test_nothing_goes_out_on_the_lan(self):
        with harness.MulticastReceiver(VISION_PORT, interface=netns.LAN_ADDRESS, bind_any=True) as lan, \
                harness.MulticastReceiver(VISION_PORT, interface=harness.LOOPBACK, bind_any=True) as lo, \
                harness.Simulator(SHIPPED_WORLD, extra_args=["--no-viewer"], local_only=True) as sim:
            received = harness.wait_for(lambda: lo.recv_from(0.5), 30, what="vision on loopback")
            self.assertEqual(received[1][0], harness.LOOPBACK)
            _, sources = frames_by_socket({"lan": lan, "lo": lo}, 1.0)
            self.assertEqual(sources["lan"] | sources["lo"], {harness.LOOPBACK})
            line = next(l for l in sim.output().splitlines() if "publishing ssl_simulation" in l)
            self.assertNotIn(netns.LAN_ADDRESS, line)
            with harness.UdpClient(host=netns.LAN_ADDRESS) as client:
                client.send(control_pb.SimulatorCommand(), CONTROL_PORT, host=netns.LAN_ADDRESS)
                self.assertIsNone(client.recv(1.0), "the control port answered on the LAN address")


if __name__ == "__main__":
    unittest.main()
