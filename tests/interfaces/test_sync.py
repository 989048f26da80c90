# SPDX-License-Identifier: Apache-2.0
"""Synchronous mode of the ssl_simulation transport over a real TCP socket: varint-delimited
SimulationSyncRequest → SimulationSyncResponse; the world steps only when asked, by whole physics
steps, and answers with the detection frames released during those steps."""
import math
import socket
import time
import unittest

import ssl_simulation_control_pb2 as control_pb
import ssl_simulation_custom_erforce_pb2 as erforce_pb
import ssl_simulation_robot_control_pb2 as robot_pb
import ssl_simulation_synchronous_pb2 as sync_pb
import ssl_gc_common_pb2 as common_pb

import test_ssl_simulation as sslsim  # helpers only (a module import brings in no test cases)


def noiseless():
    """A SimulatorCommand switching off vision noise and drop-outs (kick speeds from clean positions)."""
    cmd = control_pb.SimulatorCommand()
    r = erforce_pb.RealismConfigErForce(stddev_ball_p=0, stddev_robot_p=0, stddev_robot_phi=0,
                                        missing_ball_detections=0, missing_robot_detections=0)
    cmd.config.realism_config.custom.add().Pack(r)
    return cmd


def ball_at_mouth(cmd, rid, x, y, gap=0.0):
    """Blue robot `rid` at (x, y) facing +x, the ball `gap` m off its flat front (0.07 m ahead)."""
    sslsim.teleport_robot(cmd, common_pb.BLUE, rid, x, y, 0.0)
    cmd.control.teleport_ball.x = x + 0.07 + 0.0215 + gap
    cmd.control.teleport_ball.y = y
    return cmd


class SyncMode(unittest.TestCase):
    def setUp(self):
        self.sim = sslsim.SimProcess(sync_team="blue").start()
        self.client = sslsim.SyncClient(self.sim.sync_port)

    def tearDown(self):
        self.client.close()
        self.sim.stop()

    def errors(self, response):
        return [e.code for e in response.robot_control_response.errors]

    def test_teleported_ball_is_in_the_detections(self):
        cmd = control_pb.SimulatorCommand()
        cmd.control.teleport_ball.x = -2.0
        cmd.control.teleport_ball.y = 1.0
        r = self.client.step(0.2, command=cmd)
        self.assertEqual(self.errors(r), [])
        late = [b for b in sslsim.balls(r) if b[0] > 0.02]
        self.assertGreater(len(late), 5)
        self.assertAlmostEqual(sum(b[1] for b in late) / len(late), -2.0, delta=0.005)
        self.assertAlmostEqual(sum(b[2] for b in late) / len(late), 1.0, delta=0.005)

    def test_robot_at_1mps(self):
        cmd = noiseless()
        sslsim.teleport_robot(cmd, common_pb.BLUE, 3, 0.0, -1.0, math.pi / 2)  # facing +y
        responses = [self.client.step(0.01, command=cmd)]
        rc = robot_pb.RobotControl()
        sslsim.move_local(rc, 3, forward=1.0)
        for _ in range(150):
            r = self.client.step(0.01, rc=rc)
            self.assertEqual(self.errors(r), [])
            self.assertEqual([f.id for f in r.robot_control_response.feedback], [3])
            responses.append(r)
        track = sslsim.robot_track(responses, True, 3)
        t_end = track[-1][0]
        vx, vy = sslsim.fit_speed(track, t_end - 0.8, t_end)
        self.assertAlmostEqual(vx, 0.0, delta=0.03)
        self.assertAlmostEqual(vy, 1.0, delta=0.03)

    def test_kick_at_10mps_is_seen_at_the_clamped_6_5(self):
        r = self.client.step(0.2, command=ball_at_mouth(noiseless(), 0, -1.0, 0.0, gap=0.002))
        self.assertEqual(self.errors(r), [])
        rc = robot_pb.RobotControl()
        c = sslsim.move_local(rc, 0)
        c.kick_speed = 10.0
        c.kick_angle = 0.0
        responses = [self.client.step(0.01, rc=rc) for _ in range(40)]
        track = []
        for resp in responses:
            track += sslsim.balls(resp)
        track.sort()
        moving = [i for i in range(1, len(track)) if track[i][1] - track[i - 1][1] > 0.01]
        self.assertTrue(moving, "the ball never moved")
        i = moving[0]
        # The first pair entirely after the kick (the pair spanning it mixes rest and flight).
        (t0, x0, y0), (t1, x1, y1) = track[i], track[i + 1]
        speed = math.hypot(x1 - x0, y1 - y0) / (t1 - t0)
        self.assertGreater(speed, 6.2)  # sliding friction takes a little off within a frame or two
        self.assertLess(speed, 6.6)     # never the requested 10 m/s
        self.assertLess(abs(y1 - y0), 0.01)  # straight ahead

    def test_dribbler_contact_in_the_feedback(self):
        rc = robot_pb.RobotControl()
        c = sslsim.move_local(rc, 1)
        c.dribbler_speed = 1000.0  # rpm
        cmd = ball_at_mouth(control_pb.SimulatorCommand(), 1, 1.0, 1.0)
        seen = []
        for i in range(20):
            r = self.client.step(0.01, command=cmd if i == 0 else None, rc=rc)
            self.assertEqual([f.id for f in r.robot_control_response.feedback], [1])
            seen.append(r.robot_control_response.feedback[0].dribbler_ball_contact)
        self.assertTrue(any(seen), "no contact reported with the ball at the dribbler")
        away = control_pb.SimulatorCommand()
        away.control.teleport_ball.x = -1.0
        away.control.teleport_ball.y = -1.0
        r = self.client.step(0.05, command=away, rc=rc)
        self.assertEqual([(f.id, f.dribbler_ball_contact) for f in r.robot_control_response.feedback], [(1, False)])

    def test_world_waits_between_requests_and_steps_whole_steps(self):
        first = self.client.step(0.1)
        time.sleep(0.5)  # a real-time world would move on 0.5 s here
        second = self.client.step(0.1)
        last_first = max(f.t_capture for f in first.detection)
        captures = [f.t_capture for f in second.detection]
        self.assertTrue(captures)
        self.assertGreater(min(captures), last_first)
        self.assertLess(max(captures), 0.21)
        # 100 × 10.4 ms rounds to 100 × 10 physics steps of 1 ms: about 1.2 s in all, not 1.24.
        frames = []
        for _ in range(100):
            frames += list(self.client.step(0.0104).detection)
        newest = max(f.t_sent for f in frames)
        self.assertLess(newest, 1.202)
        self.assertGreater(newest, 1.18)

    def test_bad_requests_answer_with_codes_and_keep_the_connection(self):
        for bad in (float("nan"), -0.01, 100.0):
            r = self.client.request(sync_pb.SimulationSyncRequest(sim_step=bad))
            self.assertEqual(self.errors(r), ["UBERSIM_SYNC_INVALID_STEP"])
            self.assertEqual(len(r.detection), 0)
        rc = robot_pb.RobotControl()
        sslsim.move_local(rc, 9, forward=1.0)  # Div B: blue 0..5
        r = self.client.step(0.02, rc=rc)
        self.assertEqual(self.errors(r), ["UBERSIM_UNKNOWN_ROBOT"])
        cmd = control_pb.SimulatorCommand()
        cmd.control.teleport_ball.x = 1.0  # no y
        r = self.client.step(0.02, command=cmd)
        self.assertEqual(self.errors(r), ["UBERSIM_PARTIAL_COORD"])
        self.assertTrue(self.client.step(0.05).detection)  # still served

    def test_framing_errors_close_only_that_connection(self):
        self.assertTrue(self.client.step(0.1).detection)  # a fresh world: its cameras free-running, the first frame leaves after the 35 ms latency
        cases = {
            "varint too long": b"\xff" * 6 + b"\x01",
            "larger than the limit": sslsim.encode_varint(10 ** 6) + b"\x00" * 64,
            "garbage": sslsim.encode_varint(20) + b"\xff" * 20,
        }
        for name, data in cases.items():
            bad = sslsim.SyncClient(self.sim.sync_port)
            bad.send_raw(data)
            self.assertTrue(bad.closed_by_peer(), name)
            bad.close()
            self.assertTrue(self.client.step(0.02).detection, name)  # the first client carries on
        self.assertEqual(sslsim.codes(sslsim.control(self.sim, control_pb.SimulatorCommand())), [])
        log = self.sim.log()
        self.assertIn("bad framing", log)
        self.assertIn("bad request", log)


class Determinism(unittest.TestCase):
    """The same requests against two fresh simulators give byte-identical responses, with the
    realistic vision noise, drop-outs and radio loss of the shipped world (all seeded)."""

    @staticmethod
    def run_script():
        with sslsim.SimProcess(sync_team="blue", radio="realistic") as sim:
            client = sslsim.SyncClient(sim.sync_port)
            out = []
            cmd = control_pb.SimulatorCommand()
            cmd.control.teleport_ball.x = 0.5
            cmd.control.teleport_ball.y = 0.2
            cmd.control.teleport_ball.vx = -2.0
            cmd.control.teleport_ball.vy = 0.5
            sslsim.teleport_robot(cmd, common_pb.BLUE, 2, -1.0, 0.0, 0.0)
            out.append(client.step(0.016, command=cmd).SerializeToString())
            rc = robot_pb.RobotControl()
            sslsim.move_local(rc, 2, forward=1.5, left=0.3, angular=1.0)
            for _ in range(60):
                out.append(client.step(0.016, rc=rc).SerializeToString())
            client.close()
            return out

    def test_same_requests_give_identical_detections(self):
        a = self.run_script()
        b = self.run_script()
        frames = 0
        for ra in a:
            r = sync_pb.SimulationSyncResponse()
            r.ParseFromString(ra)
            frames += len(r.detection)
        self.assertGreater(frames, 50)
        self.assertEqual(len(a), len(b))
        for i, (ra, rb) in enumerate(zip(a, b)):
            self.assertEqual(ra, rb, "response %d differs" % i)


if __name__ == "__main__":
    unittest.main()
