# SPDX-License-Identifier: Apache-2.0
"""The grsim transport as a grSim client uses it: grSim_Packet datagrams to the simulator's
port, Robots_Status back at the sender's IP, and the effect seen in the SSL-Vision stream."""
import math
import random
import time
import unittest

import grsim_packet_pb2 as grsim_pb2
import harness
import ssl_vision_wrapper_pb2 as wrapper_pb2


def parse_vision(data):
    packet = wrapper_pb2.SSL_WrapperPacket()
    packet.ParseFromString(data)
    return packet


def command(robot_id, yellow=False, veltangent=0.0, velnormal=0.0, velangular=0.0, kickspeedx=0.0,
            kickspeedz=0.0, spinner=False):
    packet = grsim_pb2.grSim_Packet()
    packet.commands.timestamp = 0.0
    packet.commands.isteamyellow = yellow
    c = packet.commands.robot_commands.add()
    c.id = robot_id
    c.kickspeedx, c.kickspeedz = kickspeedx, kickspeedz
    c.veltangent, c.velnormal, c.velangular = veltangent, velnormal, velangular
    c.spinner = spinner
    c.wheelsspeed = False
    return packet


def robot_replacement(robot_id, x, y, dir_deg, yellow=False):
    packet = grsim_pb2.grSim_Packet()
    r = packet.replacement.robots.add()
    r.x, r.y, r.dir, r.id, r.yellowteam = x, y, dir_deg, robot_id, yellow
    return packet


def ball_replacement(**fields):
    packet = grsim_pb2.grSim_Packet()
    for key, value in fields.items():
        setattr(packet.replacement.ball, key, value)
    return packet


def find_robot(detection, robot_id, yellow=False):
    for r in (detection.robots_yellow if yellow else detection.robots_blue):
        if r.robot_id == robot_id:
            return r
    return None


class GrsimSimulation(unittest.TestCase):
    """One Division B simulator per test class, in real time, with ssl_vision and grsim on free
    ports; status goes to two more free ports on the loopback."""

    @classmethod
    def setUpClass(cls):
        cls.vision_port, cls.grsim_port, cls.blue_port, cls.yellow_port = harness.free_udp_ports(4)
        cls.world = (harness.World("div-b")
                     .add_transport("ssl_vision", port=cls.vision_port, interface=harness.LOOPBACK)
                     .add_transport("grsim", port=cls.grsim_port, status_port_blue=cls.blue_port,
                                    status_port_yellow=cls.yellow_port))
        cls.vision = harness.MulticastReceiver(cls.vision_port)
        cls.client = harness.UdpClient()
        cls.sim = harness.Simulator(cls.world).start()
        cls.vision.recv_until(lambda p: p.HasField("detection"), 10.0, parse_vision)

    @classmethod
    def tearDownClass(cls):
        cls.sim.close()
        cls.vision.close()
        cls.client.close()

    def send(self, packet):
        self.client.send(packet, self.grsim_port)

    def next_detection(self, predicate, timeout=3.0):
        """The next detection frame for which predicate(detection) holds."""
        return self.vision.recv_until(lambda p: p.HasField("detection") and predicate(p.detection),
                                      timeout, parse_vision).detection


class DriveAndReplace(GrsimSimulation):
    def test_robot_replacement_in_degrees(self):
        self.send(robot_replacement(3, 1.0, 2.0, 90.0, yellow=True))
        d = self.next_detection(lambda d: (r := find_robot(d, 3, True)) is not None
                                and abs(r.x - 1000) < 10 and abs(r.y - 2000) < 10)
        self.assertAlmostEqual(find_robot(d, 3, True).orientation, math.pi / 2, delta=0.05)

    def test_ball_replacement_and_unset_fields_keep_their_values(self):
        self.send(ball_replacement(x=1.0, y=-0.5, vx=0.0, vy=0.0))
        self.next_detection(lambda d: d.balls and abs(d.balls[0].x - 1000) < 10 and abs(d.balls[0].y + 500) < 10)
        self.send(ball_replacement(x=-0.5))  # y stays -0.5
        self.next_detection(lambda d: d.balls and abs(d.balls[0].x + 500) < 10 and abs(d.balls[0].y + 500) < 10)

    def test_robot_commanded_one_metre_per_second_forward_moves_at_one_metre_per_second(self):
        # A clear lane along y = -2.5 m, facing +x.
        self.send(robot_replacement(0, -3.5, -2.5, 0.0))
        self.next_detection(lambda d: (r := find_robot(d, 0)) is not None and abs(r.x + 3500) < 10
                            and abs(r.y + 2500) < 10)
        samples = []  # (t_capture, x, y) in s and m
        start = time.monotonic()
        next_send = start
        # Three seconds of simulated time (a busy machine may need longer in wall-clock time).
        while not samples or samples[-1][0] - samples[0][0] < 3.0:
            self.assertLess(time.monotonic() - start, 30.0, "no 3 s of vision within 30 s")
            now = time.monotonic()
            if now >= next_send:
                self.send(command(0, veltangent=1.0))  # a 60 Hz radio loop, as a team sends
                next_send += 1.0 / 60.0
            data = self.vision.recv(max(0.0, next_send - time.monotonic()))
            if data is None:
                continue
            p = parse_vision(data)
            if p.HasField("detection") and (r := find_robot(p.detection, 0)) is not None:
                samples.append((p.detection.t_capture, r.x / 1000.0, r.y / 1000.0))
        self.send(command(0))
        self.sim.assert_running()
        moving = [s for s in samples if s[0] >= samples[0][0] + 1.0]  # after speeding up (3 m/s²)
        self.assertGreater(len(moving), 100)
        t0 = moving[0][0]
        ts = [s[0] - t0 for s in moving]
        mean_t = sum(ts) / len(ts)

        def slope(values):
            mean_v = sum(values) / len(values)
            return (sum((t - mean_t) * (v - mean_v) for t, v in zip(ts, values))
                    / sum((t - mean_t) ** 2 for t in ts))

        vx, vy = slope([s[1] for s in moving]), slope([s[2] for s in moving])
        print(f"\nmeasured in vision: vx {vx:.4f} m/s, vy {vy:.4f} m/s over {ts[-1]:.2f} s")
        self.assertAlmostEqual(vx, 1.0, delta=0.05)
        self.assertAlmostEqual(vy, 0.0, delta=0.05)


class RobotStatus(GrsimSimulation):
    def test_status_goes_to_the_senders_ip_at_the_team_ports(self):
        with harness.UdpClient(self.blue_port) as blue, harness.UdpClient(self.yellow_port) as yellow:
            self.send(command(1))
            statuses = {}
            for name, sock in (("blue", blue), ("yellow", yellow)):
                got = sock.recv(3.0)
                self.assertIsNotNone(got, f"no {name} status")
                data, sender = got
                self.assertEqual(sender, ("127.0.0.1", self.grsim_port))
                status = grsim_pb2.Robots_Status()
                status.ParseFromString(data)
                statuses[name] = status
            # The first report has every robot; none touches the ball or kicked.
            for name in ("blue", "yellow"):
                self.assertEqual(sorted(s.robot_id for s in statuses[name].robots_status), list(range(6)))
                for s in statuses[name].robots_status:
                    self.assertFalse(s.infrared or s.flat_kick or s.chip_kick)
            # Later reports only name robots whose status changed: here, none.
            self.send(command(1))
            self.assertIsNone(blue.recv(0.5))
            self.assertIsNone(yellow.recv(0.1))


class BadDatagrams(GrsimSimulation):
    def positions(self, duration):
        """Mean position of every robot and the ball seen during `duration` s, mm."""
        sums = {}
        for _, p in self.vision.collect(duration, parse_vision):
            if not p.HasField("detection"):
                continue
            d = p.detection
            objects = [(("blue", r.robot_id), r) for r in d.robots_blue]
            objects += [(("yellow", r.robot_id), r) for r in d.robots_yellow]
            objects += [("ball", b) for b in d.balls[:1]]
            for key, o in objects:
                s = sums.setdefault(key, [0.0, 0.0, 0])
                s[0] += o.x
                s[1] += o.y
                s[2] += 1
        return {k: (x / n, y / n) for k, (x, y, n) in sums.items()}

    def test_malformed_datagrams_change_nothing_and_are_logged_rate_limited(self):
        before = self.positions(0.5)
        self.assertEqual(len(before), 13)  # 12 robots and the ball

        valid = command(0, veltangent=2.0).SerializeToString()
        missing = grsim_pb2.grSim_Packet()
        missing.commands.timestamp = 0.0  # isteamyellow (required) left out
        missing.commands.robot_commands.add(id=0, veltangent=2.0)
        bad = [
            valid[:-3],                                       # truncated
            missing.SerializePartialToString(),               # required fields missing
            command(2, veltangent=float("nan")).SerializeToString(),
            command(3, velangular=float("inf")).SerializeToString(),
            command(12, veltangent=2.0).SerializeToString(),  # no such robot
            command(7, yellow=True, veltangent=2.0).SerializeToString(),
            robot_replacement(4, float("nan"), 0.0, 0.0).SerializeToString(),
            robot_replacement(16, 0.0, 0.0, 0.0).SerializeToString(),  # ids are 0..15
            robot_replacement(5, 40.0, 0.0, 0.0).SerializeToString(),  # off the carpet
            ball_replacement(x=float("inf")).SerializeToString(),
            b"\x00" * 20000,                                  # longer than max_datagram
        ]
        rng = random.Random(4)
        garbage = [bytes(rng.randrange(256) for _ in range(rng.randrange(1, 300))) for _ in range(50)]
        for _ in range(20):
            for data in bad:
                self.client.send(data, self.grsim_port)
            time.sleep(0.01)  # pacing only: 100 Hz, like a team's loop
        for data in garbage:
            self.client.send(data, self.grsim_port)

        after = self.positions(1.0)
        self.sim.assert_running()
        self.assertEqual(set(after), set(before))
        for key in before:
            self.assertAlmostEqual(after[key][0], before[key][0], delta=10.0, msg=str(key))
            self.assertAlmostEqual(after[key][1], before[key][1], delta=10.0, msg=str(key))

        # Still serving: a good datagram after the bad ones works.
        self.send(ball_replacement(x=0.3, y=0.3))
        self.next_detection(lambda d: d.balls and abs(d.balls[0].x - 300) < 10 and abs(d.balls[0].y - 300) < 10)

        lines = [line for line in self.sim.output().splitlines() if "grSim datagram rejected" in line]
        self.assertGreaterEqual(len(lines), 1)
        self.assertLessEqual(len(lines), 6, "rejections are rate-limited")
        self.sim.stop()
        last = [line for line in self.sim.output().splitlines() if "grSim datagram rejected" in line][-1]
        total = int(last.rsplit(", ", 1)[1].split(" in total")[0])
        self.assertGreaterEqual(total, 20 * len(bad))


class PortInUse(unittest.TestCase):
    def test_a_taken_port_is_a_plugin_error_naming_address_and_port(self):
        with harness.UdpClient() as taken:
            port = taken.address[1]
            world = harness.World("div-b").add_transport("grsim", port=port)
            with harness.Simulator(world, fast=True, duration=1) as sim:
                code = sim.wait(30)
                out = sim.output()
        self.assertEqual(code, 4, out)
        self.assertIn(f"127.0.0.1:{port}", out)
        self.assertIn("in use", out)


if __name__ == "__main__":
    unittest.main()
