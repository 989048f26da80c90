# SPDX-License-Identifier: Apache-2.0
"""The ssl_simulation transport over real sockets: `ubersim run` in its own process, clients that
share nothing with it but the .proto files.

UDP control/blue/yellow ports answer every datagram to its sender; bad datagrams get an error
code and change nothing. What the world does is read from the synchronous mode's detections, which
also steps the world, so these tests do not depend on wall-clock timing.
"""
import math
import os
import random
import socket
import struct
import subprocess
import tempfile
import threading
import time
import unittest

import yaml

import harness
import ssl_simulation_control_pb2 as control_pb
import ssl_simulation_custom_erforce_pb2 as erforce_pb
import ssl_simulation_custom_ubersim_pb2 as ubersim_pb
import ssl_simulation_robot_control_pb2 as robot_pb
import ssl_simulation_robot_feedback_pb2 as feedback_pb
import ssl_simulation_synchronous_pb2 as sync_pb
import ssl_gc_common_pb2 as common_pb

SOURCE_DIR = os.environ.get("UBERSIM_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
BINARY = os.environ.get("UBERSIM_BINARY", "ubersim")
TIMEOUT = 3.0  # s, any single reply


def free_ports(count):
    """Ports free for both UDP and TCP right now (each socket bound to port 0 by the kernel)."""
    ports = []
    held = []
    while len(ports) < count:
        u = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        u.bind(("127.0.0.1", 0))
        port = u.getsockname()[1]
        t = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        try:
            t.bind(("127.0.0.1", port))
        except OSError:
            u.close()
            t.close()
            continue
        held += [u, t]
        ports.append(port)
    for s in held:
        s.close()
    return ports


class SimProcess:
    """`ubersim run` on a copy of a shipped world with the ssl_simulation transport on free ports."""

    def __init__(self, world="div-b", sync_team=None, perception=None, radio="ideal", extra_params=None):
        self.control_port, self.blue_port, self.yellow_port, self.sync_port = free_ports(4)
        self.tmp = tempfile.TemporaryDirectory(prefix="ubersim-sslsim-")
        doc = harness.World(world).data  # the shipped world, its paths made absolute
        params = {"plugin": "ssl_simulation", "control_port": self.control_port,
                  "blue_port": self.blue_port, "yellow_port": self.yellow_port}
        if sync_team:
            params["sync"] = {"port": self.sync_port, "team": sync_team}
        params.update(extra_params or {})
        doc["transports"] = [params]
        if perception:
            doc["perception"] = perception
        if radio:
            doc["radio"] = {"preset": radio}
        self.world = os.path.join(self.tmp.name, "world.yaml")
        with open(self.world, "w") as f:
            yaml.safe_dump(doc, f)
        self.stderr_lines = []
        self.proc = None

    def start(self):
        # Loopback only: outside a network namespace of its own a test never opens the LAN.
        self.proc = subprocess.Popen([BINARY, "run", self.world, "--quiet", "--local-only"], stdin=subprocess.DEVNULL,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        self.reader = threading.Thread(target=self._read_stderr, daemon=True)
        self.reader.start()
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError("ubersim exited early:\n" + self.log())
            try:
                udp_request(self.control_port, b"", timeout=0.3)
                return self
            except socket.timeout:
                continue
        raise RuntimeError("ssl_simulation did not answer within 30 s:\n" + self.log())

    def _read_stderr(self):
        for line in self.proc.stderr:
            self.stderr_lines.append(line.rstrip("\n"))

    def log(self):
        return "\n".join(self.stderr_lines)

    def stop(self):
        if self.proc and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=15)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        if self.proc:
            self.reader.join(timeout=5)
            self.proc.stderr.close()
        self.tmp.cleanup()

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()


def udp_request(port, payload, timeout=TIMEOUT):
    """Sends one datagram from a fresh socket and returns the reply sent back to that socket."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.settimeout(timeout)
        s.sendto(payload, ("127.0.0.1", port))
        data, _ = s.recvfrom(65536)
        return data


def control(sim, command):
    r = control_pb.SimulatorResponse()
    r.ParseFromString(udp_request(sim.control_port, command.SerializeToString()))
    return r


def robot_control(sim, port, rc, partial=False):
    data = rc.SerializePartialToString() if partial else rc.SerializeToString()
    r = feedback_pb.RobotControlResponse()
    r.ParseFromString(udp_request(port, data))
    return r


def codes(response):
    return [e.code for e in response.errors]


def teleport_robot(cmd, team, rid, x, y, orientation=0.0):
    t = cmd.control.teleport_robot.add()
    t.id.id = rid
    t.id.team = team
    t.x, t.y, t.orientation = x, y, orientation
    return t


def move_local(rc, rid, forward=0.0, left=0.0, angular=0.0):
    c = rc.robot_commands.add()
    c.id = rid
    v = c.move_command.local_velocity
    v.forward, v.left, v.angular = forward, left, angular
    return c


def realism_command(**fields):
    cmd = control_pb.SimulatorCommand()
    r = erforce_pb.RealismConfigErForce(**fields)
    any_ = cmd.config.realism_config.custom.add()
    any_.Pack(r)
    return cmd


class SyncClient:
    """Varint-delimited SimulationSyncRequest / SimulationSyncResponse over TCP."""

    def __init__(self, port, timeout=30.0):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=timeout)

    def close(self):
        self.sock.close()

    def send_raw(self, data):
        self.sock.sendall(data)

    def request(self, req):
        payload = req.SerializeToString()
        self.sock.sendall(encode_varint(len(payload)) + payload)
        return self.read_response()

    def step(self, seconds, command=None, rc=None):
        req = sync_pb.SimulationSyncRequest(sim_step=seconds)
        if command is not None:
            req.simulator_command.CopyFrom(command)
        if rc is not None:
            req.robot_control.CopyFrom(rc)
        return self.request(req)

    def read_response(self):
        length = 0
        shift = 0
        while True:
            b = self._read(1)[0]
            length |= (b & 0x7F) << shift
            shift += 7
            if not b & 0x80:
                break
        r = sync_pb.SimulationSyncResponse()
        r.ParseFromString(self._read(length))
        return r

    def _read(self, n):
        out = b""
        while len(out) < n:
            chunk = self.sock.recv(n - len(out))
            if not chunk:
                raise ConnectionError("closed by the simulator")
            out += chunk
        return out

    def closed_by_peer(self, timeout=5.0):
        """True when the simulator closes this connection within `timeout`."""
        self.sock.settimeout(timeout)
        try:
            return self.sock.recv(1) == b""
        except ConnectionResetError:
            return True
        except socket.timeout:
            return False


def encode_varint(n):
    out = b""
    while n >= 0x80:
        out += bytes([(n & 0x7F) | 0x80])
        n >>= 7
    return out + bytes([n])


def balls(response):
    """(t_capture, x m, y m) of every ball detection, in time order."""
    out = [(f.t_capture, b.x / 1000.0, b.y / 1000.0) for f in response.detection for b in f.balls]
    return sorted(out)


def robot_track(responses, team_blue, rid):
    """(t_capture, x m, y m, orientation) of one robot across responses, in time order, one per capture."""
    seen = {}
    for r in responses:
        for f in r.detection:
            for d in (f.robots_blue if team_blue else f.robots_yellow):
                if d.robot_id == rid:
                    seen[f.t_capture] = (f.t_capture, d.x / 1000.0, d.y / 1000.0, d.orientation)
    return [seen[t] for t in sorted(seen)]


def fit_speed(track, t0, t1):
    """Least-squares speed along x and y over captures in [t0, t1], m/s."""
    pts = [p for p in track if t0 <= p[0] <= t1]
    if len(pts) < 3:
        raise AssertionError("only %d detections in [%.3f, %.3f]" % (len(pts), t0, t1))
    n = len(pts)
    mt = sum(p[0] for p in pts) / n
    out = []
    for k in (1, 2):
        mv = sum(p[k] for p in pts) / n
        num = sum((p[0] - mt) * (p[k] - mv) for p in pts)
        den = sum((p[0] - mt) ** 2 for p in pts)
        out.append(num / den)
    return out


class UdpPorts(unittest.TestCase):
    """Real-time world (no sync): replies, error codes, robustness, dribbler feedback."""

    @classmethod
    def setUpClass(cls):
        cls.sim = SimProcess().start()

    @classmethod
    def tearDownClass(cls):
        cls.sim.stop()

    def test_every_datagram_gets_a_reply_to_its_sender(self):
        self.assertEqual(codes(control(self.sim, control_pb.SimulatorCommand())), [])
        for port in (self.sim.blue_port, self.sim.yellow_port):
            r = robot_control(self.sim, port, robot_pb.RobotControl())
            self.assertEqual(list(r.errors), [])
            self.assertEqual(list(r.feedback), [])

    def test_feedback_for_each_commanded_robot(self):
        rc = robot_pb.RobotControl()
        for rid in (0, 3, 5):
            move_local(rc, rid)
        r = robot_control(self.sim, self.sim.yellow_port, rc)
        self.assertEqual(codes(r), [])
        self.assertEqual(sorted(f.id for f in r.feedback), [0, 3, 5])
        self.assertTrue(all(f.HasField("dribbler_ball_contact") for f in r.feedback))

    def test_config_is_applied_or_answered_per_item(self):
        cmd = control_pb.SimulatorCommand()
        # The world's own field (Div B): acknowledged.
        cmd.config.geometry.field.field_length = 9000
        cmd.config.geometry.field.field_width = 6000
        cmd.config.geometry.field.goal_width = 1000
        cmd.config.geometry.field.goal_depth = 180
        cmd.config.geometry.field.boundary_width = 300
        spec = cmd.config.robot_specs.add()  # nothing over the model
        spec.id.id = 0
        spec.id.team = common_pb.BLUE
        cmd.config.realism_config.custom.add(type_url="type.googleapis.com/SomeoneElsesRealism", value=b"")
        self.assertEqual(codes(control(self.sim, cmd)), ["UBERSIM_UNKNOWN_REALISM_TYPE"])
        cmd = control_pb.SimulatorCommand()
        cmd.config.geometry.field.field_length = 7000
        cmd.config.geometry.field.field_width = 5000
        cmd.config.geometry.field.goal_width = 1000
        cmd.config.geometry.field.goal_depth = 180
        cmd.config.geometry.field.boundary_width = 300
        self.assertEqual(codes(control(self.sim, cmd)), ["UBERSIM_GEOMETRY_NOT_APPLIED"])
        cmd = control_pb.SimulatorCommand()
        cmd.control.teleport_ball.x = 1
        cmd.control.teleport_ball.y = 1
        cmd.control.teleport_ball.teleport_safely = True
        self.assertEqual(codes(control(self.sim, cmd)), ["UBERSIM_UNSUPPORTED_TELEPORT_SAFELY"])

    def test_bad_datagrams_get_error_replies(self):
        rc = robot_pb.RobotControl()
        c = move_local(rc, 1, forward=0.5)
        c.kick_speed = 3
        whole = rc.SerializeToString()
        rng = random.Random(7)
        garbage = bytes(rng.randrange(256) for _ in range(200))
        cases = [
            ("truncated", whole[:-3], "UBERSIM_UNREADABLE"),
            ("oversized", b"\x0a" + b"\x00" * 30000, "UBERSIM_OVERSIZED"),
            ("random", b"\xff" * 8 + garbage, "UBERSIM_UNREADABLE"),
        ]
        for name, data, code in cases:
            for port in (self.sim.blue_port, self.sim.yellow_port):
                r = feedback_pb.RobotControlResponse()
                r.ParseFromString(udp_request(port, data))
                self.assertEqual(codes(r), [code], name)
            r = control_pb.SimulatorResponse()
            r.ParseFromString(udp_request(self.sim.control_port, data))
            self.assertEqual(codes(r), [code], name)

        unknown = robot_pb.RobotControl()
        move_local(unknown, 1, forward=0.5)
        move_local(unknown, 12, forward=0.5)  # Div B has ids 0..5
        r = robot_control(self.sim, self.sim.blue_port, unknown)
        self.assertEqual(codes(r), ["UBERSIM_UNKNOWN_ROBOT"])
        self.assertEqual([f.id for f in r.feedback], [1])  # feedback for the robot that exists

        for bad in (float("nan"), float("inf"), float("-inf")):
            rc = robot_pb.RobotControl()
            move_local(rc, 2, forward=bad)
            self.assertEqual(codes(robot_control(self.sim, self.sim.blue_port, rc)), ["UBERSIM_NON_FINITE"])

        missing = robot_pb.RobotControl()
        missing.robot_commands.add().kick_speed = 2.0  # no id
        self.assertEqual(codes(robot_control(self.sim, self.sim.blue_port, missing, partial=True)),
                         ["UBERSIM_MISSING_FIELD"])

        cmd = control_pb.SimulatorCommand()
        t = cmd.control.teleport_robot.add()
        t.id.id = 1
        t.id.team = common_pb.UNKNOWN
        t.x, t.y = 0, 0
        self.assertEqual(codes(control(self.sim, cmd)), ["UBERSIM_INVALID_TEAM"])
        cmd = control_pb.SimulatorCommand()
        t = cmd.control.teleport_robot.add()
        t.id.id = 1
        t.id.team = common_pb.BLUE
        t.x = 1.0
        self.assertEqual(codes(control(self.sim, cmd)), ["UBERSIM_PARTIAL_COORD"])
        cmd = control_pb.SimulatorCommand()
        cmd.control.teleport_robot.add(x=1.0, y=1.0)  # TeleportRobot.id is required
        r = control_pb.SimulatorResponse()
        r.ParseFromString(udp_request(self.sim.control_port, cmd.SerializePartialToString()))
        self.assertEqual(codes(r), ["UBERSIM_MISSING_FIELD"])

        # Still serving everyone.
        self.assertEqual(codes(control(self.sim, control_pb.SimulatorCommand())), [])
        ok = robot_pb.RobotControl()
        move_local(ok, 0)
        for port in (self.sim.blue_port, self.sim.yellow_port):
            self.assertEqual([f.id for f in robot_control(self.sim, port, ok).feedback], [0])

    def test_flood_of_garbage_is_answered_and_logged_sparingly(self):
        before = sum("refused since the last report" in l for l in self.sim.stderr_lines)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.settimeout(TIMEOUT)
            for _ in range(200):
                s.sendto(b"\xff\xff\xff", ("127.0.0.1", self.sim.blue_port))
                r = feedback_pb.RobotControlResponse()
                r.ParseFromString(s.recvfrom(65536)[0])
                self.assertEqual(codes(r), ["UBERSIM_UNREADABLE"])
        time.sleep(0.2)
        lines = sum("refused since the last report" in l for l in self.sim.stderr_lines) - before
        self.assertGreaterEqual(lines, 0)
        self.assertLessEqual(lines, 3, self.sim.log())  # 200 refusals, at most one line a second

    def test_dribbler_contact_feedback(self):
        # Blue 4 facing +x at (1, -1); the ball against its flat front (0.07 m from the centre).
        cmd = control_pb.SimulatorCommand()
        teleport_robot(cmd, common_pb.BLUE, 4, 1.0, -1.0, 0.0)
        cmd.control.teleport_ball.x = 1.0 + 0.07 + 0.0215
        cmd.control.teleport_ball.y = -1.0
        self.assertEqual(codes(control(self.sim, cmd)), [])
        rc = robot_pb.RobotControl()
        c = move_local(rc, 4)
        c.dribbler_speed = 1000  # rpm
        deadline = time.monotonic() + 5
        contact = False
        while time.monotonic() < deadline and not contact:
            r = robot_control(self.sim, self.sim.blue_port, rc)
            contact = r.feedback[0].dribbler_ball_contact
            time.sleep(0.02)
        self.assertTrue(contact, "the dribbler never touched the ball")
        # Ball away: contact ends.
        cmd = control_pb.SimulatorCommand()
        cmd.control.teleport_ball.x = -1.0
        cmd.control.teleport_ball.y = 1.5
        control(self.sim, cmd)
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline and contact:
            contact = robot_control(self.sim, self.sim.blue_port, rc).feedback[0].dribbler_ball_contact
            time.sleep(0.02)
        self.assertFalse(contact)


class UdpWithSyncObserver(unittest.TestCase):
    """Commands over UDP, the world stepped and observed through the synchronous port."""

    def setUp(self):
        self.sim = SimProcess(sync_team="yellow").start()
        self.sync = SyncClient(self.sim.sync_port)

    def tearDown(self):
        self.sync.close()
        self.sim.stop()

    def test_teleported_ball_appears_where_it_was_put(self):
        cmd = control_pb.SimulatorCommand()
        cmd.control.teleport_ball.x = 1.25
        cmd.control.teleport_ball.y = -0.75
        self.assertEqual(codes(control(self.sim, cmd)), [])
        seen = balls(self.sync.step(0.2))
        late = [b for b in seen if b[0] > 0.05]  # after the 35 ms vision latency
        self.assertGreater(len(late), 5)
        mx = sum(b[1] for b in late) / len(late)
        my = sum(b[2] for b in late) / len(late)
        self.assertAlmostEqual(mx, 1.25, delta=0.005)
        self.assertAlmostEqual(my, -0.75, delta=0.005)

    def test_robot_commanded_at_1mps_moves_at_1mps(self):
        cmd = control_pb.SimulatorCommand()
        teleport_robot(cmd, common_pb.BLUE, 2, -2.0, 0.5, 0.0)
        self.assertEqual(codes(control(self.sim, cmd)), [])
        responses = [self.sync.step(0.01)]
        rc = robot_pb.RobotControl()
        move_local(rc, 2, forward=1.0)
        for _ in range(150):  # 1.5 s, a command every 10 ms like a team's AI
            r = robot_control(self.sim, self.sim.blue_port, rc)
            self.assertEqual(codes(r), [])
            responses.append(self.sync.step(0.01))
        track = robot_track(responses, True, 2)
        t_end = track[-1][0]
        vx, vy = fit_speed(track, t_end - 0.8, t_end)
        self.assertAlmostEqual(vx, 1.0, delta=0.05)
        self.assertAlmostEqual(vy, 0.0, delta=0.05)

        # The robot's own account in its RobotFeedback: what its drive measured (custom, an
        # UberSimDriveFeedback), agreeing with what the cameras saw.
        (feedback,) = r.feedback
        self.assertEqual(feedback.custom.type_url, "type.googleapis.com/UberSimDriveFeedback")
        drive = ubersim_pb.UberSimDriveFeedback()
        self.assertTrue(feedback.custom.Unpack(drive))
        self.assertAlmostEqual(drive.forward, 1.0, delta=0.05)
        self.assertAlmostEqual(drive.left, 0.0, delta=0.05)
        self.assertAlmostEqual(drive.angular, 0.0, delta=0.1)
        self.assertEqual(len(drive.wheel_speeds), 4)
        # Driving straight ahead at 1 m/s, each wheel rolls at v |sin(angle)| / r (ssl-omni-2026:
        # wheels at 60, 135, 225, 300 deg, r = 29 mm), the front pair and the back pair each
        # turning opposite ways.
        w = list(drive.wheel_speeds)
        for speed, angle in zip(w, (60, 135, 225, 300)):
            self.assertAlmostEqual(abs(speed), abs(math.sin(math.radians(angle))) / 0.029,
                                   delta=0.08 * abs(math.sin(math.radians(angle))) / 0.029, msg=w)
        self.assertLess(w[0] * w[3], 0.0, w)
        self.assertLess(w[1] * w[2], 0.0, w)

    def test_bad_datagrams_change_nothing(self):
        before = self.positions(self.sync.step(0.1))
        rc = robot_pb.RobotControl()
        move_local(rc, 9, forward=2.0)   # not on the field: that command only
        self.assertEqual(codes(robot_control(self.sim, self.sim.blue_port, rc)), ["UBERSIM_UNKNOWN_ROBOT"])
        rc = robot_pb.RobotControl()
        move_local(rc, 1, forward=2.0, angular=float("nan"))
        robot_control(self.sim, self.sim.yellow_port, rc)
        cmd = control_pb.SimulatorCommand()
        cmd.control.teleport_ball.x = float("inf")
        cmd.control.teleport_ball.y = 0
        self.assertEqual(codes(control(self.sim, cmd)), ["UBERSIM_NON_FINITE"])
        good = rc.SerializeToString()
        for data in (good[:-2], b"\x00" * 40000, bytes(range(256))):
            for port in (self.sim.control_port, self.sim.blue_port, self.sim.yellow_port):
                udp_request(port, data)
        after = self.positions(self.sync.step(0.3))
        self.assertEqual(before.keys(), after.keys())
        for key in before:
            self.assertAlmostEqual(before[key][0], after[key][0], delta=0.01, msg=key)
            self.assertAlmostEqual(before[key][1], after[key][1], delta=0.01, msg=key)

    def test_valid_teleports_apply_beside_invalid_ones_with_one_error_each(self):
        cmd = control_pb.SimulatorCommand()
        teleport_robot(cmd, common_pb.BLUE, 0, 1.5, 1.0)               # valid: moves
        teleport_robot(cmd, common_pb.BLUE, 1, float("nan"), 0.0)      # invalid: one error
        teleport_robot(cmd, common_pb.BLUE, 9, 0.0, 0.0)               # not on the field: quiet
        teleport_robot(cmd, common_pb.YELLOW, 0, -1.5, -1.0)           # valid: moves
        cmd.control.teleport_ball.x = 0.5                              # partial: one error
        self.assertEqual(sorted(codes(control(self.sim, cmd))), ["UBERSIM_NON_FINITE", "UBERSIM_PARTIAL_COORD"])
        after = self.positions(self.sync.step(0.2))
        self.assertAlmostEqual(after["blue 0"][0], 1.5, delta=0.05)
        self.assertAlmostEqual(after["yellow 0"][0], -1.5, delta=0.05)
        self.assertNotIn("blue 9", after)

    @staticmethod
    def positions(response):
        """Last detection of the ball and of each robot: name → (x, y) in m."""
        out = {}
        for f in sorted(response.detection, key=lambda f: f.t_capture):
            for b in f.balls:
                out["ball"] = (b.x / 1000, b.y / 1000)
            for team, robots in (("blue", f.robots_blue), ("yellow", f.robots_yellow)):
                for d in robots:
                    out["%s %d" % (team, d.robot_id)] = (d.x / 1000, d.y / 1000)
        return out

    def test_realism_changes_take_effect(self):
        # Latency: a frame leaves the perception pipeline vision_delay after its capture.
        for delay_ms in (20, 60):
            self.assertEqual(codes(control(self.sim, realism_command(vision_delay=delay_ms * 1000000))), [])
            r = self.sync.step(0.3)
            frames = [f for f in r.detection if f.t_capture > r.detection[-1].t_capture - 0.15]
            self.assertTrue(frames)
            for f in frames:
                self.assertAlmostEqual(f.t_sent - f.t_capture, delay_ms / 1000.0, delta=1e-6)
        # Noise: none, then 5 cm on the ball.
        quiet = realism_command(stddev_ball_p=0.0, missing_ball_detections=0.0)
        self.assertEqual(codes(control(self.sim, quiet)), [])
        self.sync.step(0.1)
        still = balls(self.sync.step(0.3))
        self.assertGreater(len(still), 10)
        spread = max(b[1] for b in still) - min(b[1] for b in still)
        self.assertLess(spread, 0.0005, "a resting ball without noise is seen in one place")
        self.assertEqual(codes(control(self.sim, realism_command(stddev_ball_p=0.05))), [])
        self.sync.step(0.1)
        noisy = balls(self.sync.step(0.3))
        spread = max(b[1] for b in noisy) - min(b[1] for b in noisy)
        self.assertGreater(spread, 0.05)
        # Every field applies, none is refused as unsupported: the processing time is what the
        # frames stamp as t_sent - t_capture, and the ball's blob area carries its noise.
        got = control(self.sim, realism_command(vision_delay=30000000, vision_processing_time=8000000,
                                                stddev_ball_area=0.0))
        self.assertEqual(codes(got), [])
        self.sync.step(0.1)
        r = self.sync.step(0.3)
        self.assertAlmostEqual(r.detection[-1].t_sent - r.detection[-1].t_capture, 0.008, delta=1e-6)
        quiet_areas = {b.area for f in r.detection for b in f.balls}
        self.assertEqual(len(quiet_areas), 1, quiet_areas)  # a resting ball: one blob size
        self.assertGreater(min(quiet_areas), 0)
        self.assertEqual(codes(control(self.sim, realism_command(stddev_ball_area=6.5))), [])
        self.sync.step(0.1)
        noisy_areas = [b.area for f in self.sync.step(0.3).detection for b in f.balls]
        self.assertGreater(len(set(noisy_areas)), 3, noisy_areas)

    def test_lost_feedback_leaves_the_robot_out_of_the_response(self):
        rc = robot_pb.RobotControl()
        move_local(rc, 2)
        self.sync.step(0.01)
        self.assertEqual([f.id for f in robot_control(self.sim, self.sim.blue_port, rc).feedback], [2])
        # robot_response_loss 1: every robot's answer is lost, the response still comes.
        self.assertEqual(codes(control(self.sim, realism_command(robot_response_loss=1.0))), [])
        self.sync.step(0.01)
        r = robot_control(self.sim, self.sim.blue_port, rc)
        self.assertEqual(codes(r), [])
        self.assertEqual(list(r.feedback), [])
        self.assertEqual(codes(control(self.sim, realism_command(robot_response_loss=0.0))), [])
        self.sync.step(0.01)
        self.assertEqual([f.id for f in robot_control(self.sim, self.sim.blue_port, rc).feedback], [2])


if __name__ == "__main__":
    unittest.main()
