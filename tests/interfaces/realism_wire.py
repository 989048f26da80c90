# SPDX-License-Identifier: Apache-2.0
"""The league's realism presets measured through the wire (issue 35, item 4).

`ubersim run WORLD --realism PRESET --local-only` in its own process; everything is read from what
a team's software receives: SSL_WrapperPacket datagrams on the vision multicast group (joined on
loopback, where --local-only sends them), SimulationSyncResponse and RobotControlResponse. Used by
test_realism_wire.py (assertions) and tools/realism_report.py (docs/validation/realism.md).

The world is a shipped one (div-b: one camera 6 m above the centre; div-a: two cameras over the
halves) with its transports on free ports and its own perception block as shipped (ÜberSim's
`realistic`, whose four effects beyond the league's model a league preset switches off: the
figures show that `--realism` gives the league's preset exactly; docs/interfaces.md, "Realism
presets side by side").

Most figures come from the synchronous mode: the test steps the world, so nothing depends on the
machine keeping real time, and every frame's simulated send time is known. Only the arrival of
the datagrams against the wall clock is measured in a real-time run (`RealTimeWorld`).
"""
import math
import statistics
import time

import harness
import ssl_gc_common_pb2 as common_pb
import ssl_simulation_control_pb2 as control_pb
import ssl_simulation_custom_erforce_pb2 as erforce_pb
import ssl_simulation_robot_control_pb2 as robot_pb
import ssl_simulation_robot_feedback_pb2 as feedback_pb
import ssl_vision_wrapper_pb2 as wrapper_pb
import test_ssl_simulation as sslsim  # helpers only (a module import brings in no test cases)

# The league's presets: ER-Force's config/simulator-realism/*.txt, every RealismConfigErForce field
# (reference/ssl-protocols.md §6.1), in the wire's units (m, rad, px, 1/s per robot, ns). Written
# out here from the reference, not read from the simulator, so the test compares against the
# league's numbers.
LEAGUE_PRESETS = {
    "None": dict(stddev_ball_p=0.0, stddev_robot_p=0.0, stddev_robot_phi=0.0, stddev_ball_area=0.0,
                 enable_invisible_ball=True, ball_visibility_threshold=0.4, camera_overlap=0.3,
                 dribbler_ball_detections=0.0, camera_position_error=0.0, robot_command_loss=0.0,
                 robot_response_loss=0.0, missing_ball_detections=0.0, vision_delay=35_000_000,
                 vision_processing_time=5_000_000, simulate_dribbling=True, object_position_offset=0.0,
                 missing_robot_detections=0.0, command_delay=0),
    "Friendly": dict(stddev_ball_p=0.0004, stddev_robot_p=0.0003, stddev_robot_phi=0.003, stddev_ball_area=1.0,
                     enable_invisible_ball=True, ball_visibility_threshold=0.4, camera_overlap=1.0,
                     dribbler_ball_detections=0.001, camera_position_error=0.05, robot_command_loss=0.01,
                     robot_response_loss=0.01, missing_ball_detections=0.05, vision_delay=35_000_000,
                     vision_processing_time=10_000_000, simulate_dribbling=True, object_position_offset=0.02,
                     missing_robot_detections=0.02, command_delay=0),
    "RC2021": dict(stddev_ball_p=0.0010, stddev_robot_p=0.0013, stddev_robot_phi=0.01, stddev_ball_area=6.5,
                   enable_invisible_ball=True, ball_visibility_threshold=0.4, camera_overlap=1.0,
                   dribbler_ball_detections=0.02, camera_position_error=0.0, robot_command_loss=0.03,
                   robot_response_loss=0.1, missing_ball_detections=0.05, vision_delay=35_000_000,
                   vision_processing_time=10_000_000, simulate_dribbling=False, object_position_offset=0.0,
                   missing_robot_detections=0.0, command_delay=0),
    "Realistic": dict(stddev_ball_p=0.0014, stddev_robot_p=0.0013, stddev_robot_phi=0.01, stddev_ball_area=6.5,
                      enable_invisible_ball=True, ball_visibility_threshold=0.4, camera_overlap=1.0,
                      dribbler_ball_detections=0.05, camera_position_error=0.1, robot_command_loss=0.03,
                      robot_response_loss=0.1, missing_ball_detections=0.05, vision_delay=35_000_000,
                      vision_processing_time=10_000_000, simulate_dribbling=True, object_position_offset=0.02,
                      missing_robot_detections=0.02, command_delay=3_000_000),
}

PHYSICS_STEP = 0.005  # s: the shipped worlds' `fast` profile, written into the copy so the test knows it
MAX_STEP = 2.0        # s: the longest synchronous request the copy accepts
BALL_RADIUS = 0.0215  # m: the shipped golf ball
ROBOT_RADIUS = 0.09   # m: ssl-omni-2026
ROBOT_FRONT = 0.07    # m: its centre to its flat front
FOCAL_LENGTH_PX = 390.0  # the blob area's focal length (reference/ssl-protocols.md §6.2)
CAMERA_ERROR_DIRECTION = (0.3, 0.7, 0.05)
NEAR = 0.05           # m: a ball detection this close to where the ball lies is the ball


def wrap(angle):
    """An angle in (-π, π]."""
    return math.atan2(math.sin(angle), math.cos(angle))


def parse(data):
    packet = wrapper_pb.SSL_WrapperPacket()
    packet.ParseFromString(data)
    return packet


def realism_any(fields):
    """A SimulatorCommand carrying one RealismConfigErForce with `fields` (wire units)."""
    cmd = control_pb.SimulatorCommand()
    cmd.config.realism_config.custom.add().Pack(erforce_pb.RealismConfigErForce(**fields))
    return cmd


def league_world(name, vision_port, ports=None, sync_port=None):
    """A copy of shipped world NAME with ssl_vision (loopback) and ssl_simulation on the given ports,
    ÜberSim's extra vision effects off and the physics step written out."""
    w = harness.World(name)
    w.add_transport("ssl_vision", port=vision_port, interface=harness.LOOPBACK)
    if ports:
        params = dict(control_port=ports[0], blue_port=ports[1], yellow_port=ports[2])
        if sync_port:
            params["sync"] = {"port": sync_port, "team": "blue", "max_step": MAX_STEP}
        w.add_transport("ssl_simulation", **params)
    w.data.setdefault("physics", {})["step"] = PHYSICS_STEP
    return w


class Frame:
    """One detection frame as received on the multicast group (`wire`, mm and Unix stamps), with
    the simulated send time the synchronous response gave the same frame (`t_sent`, s)."""

    __slots__ = ("wire", "t_sent", "request")

    def __init__(self, wire, t_sent, request):
        self.wire = wire
        self.t_sent = t_sent
        self.request = request

    def balls(self):
        """[(x m, y m, area px)]"""
        return [(b.x / 1000.0, b.y / 1000.0, b.area) for b in self.wire.balls]

    def robots(self):
        """{(team, id): (x m, y m, orientation)}"""
        out = {("blue", r.robot_id): (r.x / 1000.0, r.y / 1000.0, r.orientation) for r in self.wire.robots_blue}
        out.update({("yellow", r.robot_id): (r.x / 1000.0, r.y / 1000.0, r.orientation)
                    for r in self.wire.robots_yellow})
        return out


class _Session:
    """A simulator with the sockets a test opened to it: closed together, also as a context manager."""

    def _sockets(self):
        return ()

    def close(self):
        for sock in self._sockets():
            if sock:
                sock.close()
        self.sim.close()
        self.receiver.close()

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.close()
        return False


class SyncWorld(_Session):
    """`ubersim run COPY --realism PRESET --local-only` with the synchronous mode on: every request
    steps the world and the frames it released are collected from the multicast group."""

    def __init__(self, preset, world="div-b"):
        self.preset = preset
        self.vision_port, control, blue, yellow, self.sync_port = sslsim.free_ports(5)
        self.control_port, self.blue_port, self.yellow_port = control, blue, yellow
        self.world = league_world(world, self.vision_port, (control, blue, yellow), self.sync_port)
        self.receiver = harness.MulticastReceiver(self.vision_port)
        self.sim = harness.Simulator(self.world, extra_args=["--realism", preset])
        self.client = None
        self.team = None
        self.geometries = []      # every geometry packet received
        self.mismatches = []      # frames whose multicast copy differs from the synchronous one
        self.steps = 0            # physics steps asked for so far
        self.requests = 0
        self.start_bounds = [-math.inf, math.inf]  # the simulated time the first request started at
        self._early = {}

    def start(self):
        def connect():
            self.sim.assert_running()
            try:
                return sslsim.SyncClient(self.sync_port, timeout=60.0)
            except OSError:
                return None

        try:
            self.sim.start()
            self.client = harness.wait_for(connect, 30.0, interval=0.05, what="the synchronous port")
            self.team = harness.UdpClient()
        except BaseException:
            self.close()
            raise
        return self

    def _sockets(self):
        return (self.client, self.team)

    def command_line(self):
        return "ubersim run <copy of models/worlds/%s.yaml> --realism %s --local-only" % (
            self.world.data["name"], self.preset)

    def step(self, seconds, command=None, rc=None):
        """One synchronous request; returns (response, [Frame]) with the frames it released, as
        received on the multicast group, in release order."""
        steps_before = self.steps
        if seconds > 0:
            self.steps += max(1, round(seconds / PHYSICS_STEP))
        response = self.client.step(seconds, command=command, rc=rc)
        self.requests += 1
        # The frames it released have t_sent in (end of the previous request, end of this one]:
        # that bounds the simulated time the first request started at.
        for d in response.detection:
            self.start_bounds[0] = max(self.start_bounds[0], d.t_sent - self.steps * PHYSICS_STEP)
            self.start_bounds[1] = min(self.start_bounds[1], d.t_sent - steps_before * PHYSICS_STEP)
        frames = []
        for d in response.detection:
            key = (d.camera_id, d.frame_number)
            wire = self._receive(key)
            if not same_frame(wire, d):
                self.mismatches.append(key)
            frames.append(Frame(wire, d.t_sent, self.requests))
        return response, frames

    def request_start(self):
        """The simulated time the next request starts at, s. The world's time is a whole number of
        steps, and the released frames bound where the first request started (start_bounds):
        the one multiple of the step in those bounds."""
        lo, hi = self.start_bounds
        n = math.ceil(lo / PHYSICS_STEP - 1e-6)
        if not (n * PHYSICS_STEP < hi - 1e-9 and (n + 1) * PHYSICS_STEP >= hi - 1e-9):
            raise AssertionError("the start of the synchronous steps is not pinned down: %r" % (self.start_bounds,))
        return (n + self.steps) * PHYSICS_STEP

    def _receive(self, key):
        if key in self._early:
            return self._early.pop(key)
        deadline = time.monotonic() + 10.0
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise AssertionError("frame %s of the synchronous response never came on the multicast group" % (key,))
            data = self.receiver.recv(left)
            if data is None:
                continue
            p = parse(data)
            if p.HasField("geometry"):
                self.geometries.append(p.geometry)
                continue
            got = (p.detection.camera_id, p.detection.frame_number)
            if got == key:
                return p.detection
            self._early[got] = p.detection

    def geometry(self, timeout=10.0):
        """The newest geometry packet; waits for the first (sent as the transport starts, then
        every geometry_interval of wall-clock time)."""
        deadline = time.monotonic() + timeout
        while not self.geometries:
            left = deadline - time.monotonic()
            if left <= 0:
                raise AssertionError("no geometry packet within %s s" % timeout)
            data = self.receiver.recv(left)
            if data is None:
                continue
            p = parse(data)
            if p.HasField("geometry"):
                self.geometries.append(p.geometry)
            else:
                self._early[(p.detection.camera_id, p.detection.frame_number)] = p.detection
        return self.geometries[-1]

    def run(self, seconds, chunk=MAX_STEP):
        """Steps `seconds` of simulated time in requests of at most `chunk`; all the frames."""
        frames = []
        left = seconds
        while left > 1e-9:
            now = min(chunk, left)
            frames += self.step(now)[1]
            left -= now
        return frames

    def control(self, command):
        """A SimulatorCommand over UDP; its error codes."""
        return sslsim.codes(sslsim.control(self, command))

    def yellow_control(self, rc):
        """A RobotControl for the yellow team over UDP; the RobotControlResponse."""
        self.team.send(rc, self.yellow_port)
        reply = self.team.recv(10.0)
        assert reply is not None, "no RobotControlResponse:\n" + self.sim.output()
        r = feedback_pb.RobotControlResponse()
        r.ParseFromString(reply[0])
        return r

    def placements(self):
        """{(team, id): (x, y, yaw)} where the world file puts the robots."""
        return {(r["team"], r["id"]): (r["x"], r["y"], r.get("yaw", 0.0)) for r in self.world.robots()}

    def ball_start(self):
        x, y = self.world.data.get("ball_start", [0.0, 0.0, 0.0])[:2]
        return x, y


def same_frame(wire, sync):
    """The multicast copy and the synchronous copy of a frame report the same objects (mm)."""
    def key(frame):
        balls = sorted((round(b.x, 3), round(b.y, 3), b.area) for b in frame.balls)
        robots = sorted((team, r.robot_id, round(r.x, 3), round(r.y, 3), round(r.orientation, 6))
                        for team, rs in (("b", frame.robots_blue), ("y", frame.robots_yellow)) for r in rs)
        return balls, robots
    return key(wire) == key(sync)


# ------------------------------------------------------------------------------------------------
# Statistics


def detrended_sigma(series, angles=False):
    """σ of the scatter about each series' own straight line (least squares in time), pooled:
    sqrt(Σ residual² / (N − 2·series)). `series` is a list of [(t, value)]. The line takes out
    what a standing robot does by itself (it creeps by a fraction of a millimetre per second),
    which white noise of any σ does not change. Angles are unwrapped about their circular mean
    first. Returns (σ, N, largest |residual|)."""
    total, n, k, largest = 0.0, 0, 0, 0.0
    for points in series:
        if len(points) < 3:
            continue
        ts = [p[0] for p in points]
        vs = [p[1] for p in points]
        if angles:
            c = math.atan2(sum(math.sin(v) for v in vs), sum(math.cos(v) for v in vs))
            vs = [wrap(v - c) for v in vs]
        mt, mv = statistics.fmean(ts), statistics.fmean(vs)
        stt = sum((t - mt) ** 2 for t in ts)
        slope = sum((t - mt) * (v - mv) for t, v in zip(ts, vs)) / stt if stt > 0 else 0.0
        for t, v in zip(ts, vs):
            r = v - mv - slope * (t - mt)
            total += r * r
            largest = max(largest, abs(r))
        n += len(points)
        k += 2
    return (math.sqrt(total / (n - k)) if n > k else float("nan")), n, largest


def line_at(points, t0):
    """The least-squares line through [(t, value)] evaluated at t0."""
    ts = [p[0] for p in points]
    vs = [p[1] for p in points]
    mt, mv = statistics.fmean(ts), statistics.fmean(vs)
    stt = sum((t - mt) ** 2 for t in ts)
    slope = sum((t - mt) * (v - mv) for t, v in zip(ts, vs)) / stt if stt > 0 else 0.0
    return mv + slope * (t0 - mt), slope


def normal_cdf(z):
    return 0.5 * (1.0 + math.erf(z / math.sqrt(2.0)))


def area_fit(areas):
    """(μ, σ) of a Gaussian whose samples are reported as round(max(0, x)), the way the ball's blob
    area is (docs/interfaces.md: never below 0, whole pixels): maximum likelihood, so neither the
    rounding nor the many zeros of a small blob with much noise bias σ. One value only: σ = 0."""
    counts = {}
    for a in areas:
        counts[a] = counts.get(a, 0) + 1
    if len(counts) == 1:
        return float(areas[0]), 0.0

    def nll(mu, sigma):
        if sigma <= 0:
            return math.inf
        total = 0.0
        for k, n in counts.items():
            hi = normal_cdf((k + 0.5 - mu) / sigma)
            lo = 0.0 if k == 0 else normal_cdf((k - 0.5 - mu) / sigma)
            total -= n * math.log(max(hi - lo, 1e-300))
        return total

    # Nelder-Mead in (μ, log σ) from the plain moments.
    mu0 = statistics.fmean(areas)
    s0 = max(statistics.pstdev(areas), 0.3)
    pts = [(mu0, math.log(s0)), (mu0 + 1.0, math.log(s0)), (mu0, math.log(s0) + 0.3)]
    f = lambda p: nll(p[0], math.exp(p[1]))  # noqa: E731
    vals = [f(p) for p in pts]
    for _ in range(400):
        order = sorted(range(3), key=lambda i: vals[i])
        pts = [pts[i] for i in order]
        vals = [vals[i] for i in order]
        if abs(vals[2] - vals[0]) < 1e-10 and max(abs(pts[2][0] - pts[0][0]), abs(pts[2][1] - pts[0][1])) < 1e-7:
            break
        c = ((pts[0][0] + pts[1][0]) / 2, (pts[0][1] + pts[1][1]) / 2)
        r = (2 * c[0] - pts[2][0], 2 * c[1] - pts[2][1])
        fr = f(r)
        if fr < vals[0]:
            e = (3 * c[0] - 2 * pts[2][0], 3 * c[1] - 2 * pts[2][1])
            fe = f(e)
            pts[2], vals[2] = (e, fe) if fe < fr else (r, fr)
        elif fr < vals[1]:
            pts[2], vals[2] = r, fr
        else:
            k = ((c[0] + pts[2][0]) / 2, (c[1] + pts[2][1]) / 2)
            fk = f(k)
            if fk < vals[2]:
                pts[2], vals[2] = k, fk
            else:
                for i in (1, 2):
                    pts[i] = ((pts[0][0] + pts[i][0]) / 2, (pts[0][1] + pts[i][1]) / 2)
                    vals[i] = f(pts[i])
    best = min(range(3), key=lambda i: vals[i])
    return pts[best][0], math.exp(pts[best][1])


def binomial_band(p, n, k=4.0):
    """[p - k·SE, p + k·SE] for a rate measured from n trials; SE from the promised p (at least
    one trial's worth, so p = 0 allows no event and p = 1 no miss)."""
    se = math.sqrt(p * (1.0 - p) / n) if n else math.inf
    return max(0.0, p - k * se), min(1.0, p + k * se)


def poisson_band(expected, k=4.0):
    """[λ - k√λ, λ + k√λ] counts, the upper end at least 1 when λ > 0 (a rare event may happen once)."""
    if expected <= 0:
        return 0.0, 0.0
    spread = k * math.sqrt(expected)
    return max(0.0, expected - spread), max(1.0, expected + spread)


# ------------------------------------------------------------------------------------------------
# Measurements (synchronous)


def measure_still(world, seconds):
    """Robots standing where the world file puts them, the ball resting at its start; no command.
    Everything the frames of `seconds` of simulated time say about noise, drop-outs, false balls,
    the blob area and the stamps."""
    world.run(0.5)  # the robots settle on their wheels
    frames = world.run(seconds)
    placed = world.placements()
    bx, by = world.ball_start()
    cameras = sorted({f.wire.camera_id for f in frames})
    per_camera_frames = {c: sum(f.wire.camera_id == c for f in frames) for c in cameras}
    out = {"frames": len(frames), "cameras": cameras, "frames_per_camera": per_camera_frames}
    t = sorted(f.t_sent for f in frames if f.wire.camera_id == cameras[0])
    out["frame_period"] = (t[-1] - t[0]) / (len(t) - 1)
    out["seconds"] = len(t) * out["frame_period"]  # simulated time the frames of one camera cover
    t_first = min(f.t_sent for f in frames)

    # Robots, per camera and robot (a robot in two cameras' parts is two series, each with its noise).
    series = {}
    for f in frames:
        for key, pose in f.robots().items():
            series.setdefault((f.wire.camera_id, key), []).append((f.t_sent,) + pose)
    seen_by = {}
    for cam, key in series:
        seen_by.setdefault(key, set()).add(cam)
    slots = sum(per_camera_frames[c] for cams in seen_by.values() for c in cams)
    out["robot_slots"] = slots
    out["robot_missing"] = slots - sum(len(v) for v in series.values())
    out["robots_seen"] = sorted(seen_by)
    out["robots_placed"] = sorted(placed)
    xs = [[(p[0], p[1]) for p in v] for v in series.values()]
    ys = [[(p[0], p[2]) for p in v] for v in series.values()]
    out["robot_sigma"], out["robot_samples"], out["robot_largest"] = detrended_sigma(xs + ys)
    out["robot_phi_sigma"], _, out["robot_phi_largest"] = detrended_sigma(
        [[(p[0], p[3]) for p in v] for v in series.values()], angles=True)
    # Where each robot was seen at the start against where the world file puts it (the systematic
    # offset, zero for a camera above the centre), and how fast it creeps by itself.
    offsets, creep = {}, 0.0
    for (cam, key), v in series.items():
        x0, y0, _ = placed[key]
        x, vx = line_at([(p[0], p[1]) for p in v], t_first)
        y, vy = line_at([(p[0], p[2]) for p in v], t_first)
        offsets[(cam, key)] = (x - x0, y - y0)
        creep = max(creep, math.hypot(vx, vy))
    out["robot_start_offsets"] = offsets
    out["robot_creep"] = creep

    # The ball: the detection near where it lies; any other is a false ball.
    ball = {c: [] for c in cameras}
    false_balls = []
    for f in frames:
        for b in f.balls():
            if math.hypot(b[0] - bx, b[1] - by) < NEAR:
                ball[f.wire.camera_id].append((f.t_sent,) + b)
            else:
                false_balls.append((f.t_sent, f.wire.camera_id) + b)
    with_ball = sum(len({p[0] for p in v}) for v in ball.values())
    out["ball_frames"] = len(frames)
    out["ball_missing"] = len(frames) - with_ball
    out["ball_double"] = sum(len(v) for v in ball.values()) - with_ball
    out["ball_sigma"], out["ball_samples"], _ = detrended_sigma(
        [[(p[0], p[1]) for p in v] for v in ball.values()] + [[(p[0], p[2]) for p in v] for v in ball.values()])
    xs_all = [p[1] for v in ball.values() for p in v]
    ys_all = [p[2] for v in ball.values() for p in v]
    out["ball_spread"] = max(max(xs_all) - min(xs_all), max(ys_all) - min(ys_all))
    out["ball_mean_offsets"] = {c: (statistics.fmean(p[1] for p in v) - bx, statistics.fmean(p[2] for p in v) - by)
                                for c, v in ball.items() if v}
    areas = [p[3] for v in ball.values() for p in v]
    out["ball_area_values"] = len(set(areas))
    out["ball_area_mu"], out["ball_area_sigma"] = area_fit(areas)
    ball_distance = math.hypot(math.hypot(bx, by), 6.0 - BALL_RADIUS)  # from a camera 6 m above it
    out["ball_area_expected_mean"] = math.pi * (FOCAL_LENGTH_PX * BALL_RADIUS / ball_distance) ** 2

    # False balls: each against the dribbler corners of the robots the same camera reports, where
    # each robot stood at that moment (its fitted line: the robots creep).
    side = math.sqrt(ROBOT_RADIUS ** 2 - ROBOT_FRONT ** 2)
    tracks = {}
    for (cam, key), v in series.items():
        yaw = math.atan2(sum(math.sin(p[3]) for p in v), sum(math.cos(p[3]) for p in v))
        x0, vx = line_at([(p[0], p[1]) for p in v], t_first)
        y0, vy = line_at([(p[0], p[2]) for p in v], t_first)
        tracks[(cam, key)] = (x0, vx, y0, vy, yaw)
    at_corner = 0
    for t, cam, x, y, _ in false_balls:
        best = math.inf
        for (c, key), (x0, vx, y0, vy, yaw) in tracks.items():
            if c != cam:
                continue
            mx, my = x0 + vx * (t - t_first), y0 + vy * (t - t_first)
            for s in (side, -side):
                cx = mx + ROBOT_FRONT * math.cos(yaw) - s * math.sin(yaw)
                cy = my + ROBOT_FRONT * math.sin(yaw) + s * math.cos(yaw)
                best = min(best, math.hypot(x - cx, y - cy))
        at_corner += best < 0.002
    out["false_balls"] = len(false_balls)
    out["false_balls_at_corner"] = at_corner
    # Each camera draws false balls for every robot it reports: exposure per camera and robot.
    out["robot_seconds"] = sum(len(cams) for cams in seen_by.values()) * out["seconds"]

    # The stamps: t_sent - t_capture as the frames say.
    stamped = [f.wire.t_sent - f.wire.t_capture for f in frames]
    out["processing_min"], out["processing_max"] = min(stamped), max(stamped)
    return out


def measure_delay(world, trials=8):
    """vision_delay = t_sent − true capture, from the ball teleported between two spots (1 m
    apart). A frame that still shows the old spot was captured at or before the end of the step
    before the teleport (T0), one that shows the new spot at the end of a later step (≥ T0 + one
    step): t_sent − T0 bounds the delay from below for the last old frame, t_sent − T0 − step
    from above for the first new one. Each trial starts at another phase of the camera's period
    and the bounds of all trials are intersected. T0 is simulated time, known from the whole
    steps asked for (the synchronous mode) and where the responses' frames fall. Returns
    (lower, upper) in s."""
    spots = [(0.5, -0.5), (-0.5, -0.5)]
    lower, upper = -math.inf, math.inf
    world.step(0.2, command=teleport_ball(*spots[1]))
    world.run(0.2)
    for trial in range(trials):
        old, new = spots[(trial + 1) % 2], spots[trial % 2]
        world.step(PHYSICS_STEP * (3 + trial))  # a different phase each time
        t0 = world.request_start()
        _, frames = world.step(0.2, command=teleport_ball(*new))
        frames += world.step(0.1)[1]
        last_old = max((f.t_sent for f in frames if ball_near(f, old)), default=None)
        first_new = min((f.t_sent for f in frames if ball_near(f, new)), default=None)
        if last_old is not None:
            lower = max(lower, last_old - t0)
        if first_new is not None:
            upper = min(upper, first_new - t0 - PHYSICS_STEP)
    return lower, upper


def teleport_ball(x, y):
    cmd = control_pb.SimulatorCommand()
    cmd.control.teleport_ball.x = x
    cmd.control.teleport_ball.y = y
    return cmd


def ball_near(frame, spot, within=NEAR):
    return any(math.hypot(b[0] - spot[0], b[1] - spot[1]) < within for b in frame.balls())


def measure_occlusion(world, seconds):
    """The ball 3 m from the camera's nadir with a robot right in front of it, on the line to the
    nadir (its back to the ball, 1 cm away): the fraction of frames with the ball; then with the
    robot beside the ball, off that line."""
    ball = (3.0, 0.0)
    robot_key = ("blue", 0)
    behind = ball[0] - BALL_RADIUS - ROBOT_RADIUS - 0.01
    out = {"ball": ball, "robot": robot_key}
    for name, (x, y) in (("hidden", (behind, 0.0)), ("aside", (ball[0], 0.5))):
        cmd = teleport_ball(*ball)
        sslsim.teleport_robot(cmd, common_pb.BLUE, robot_key[1], x, y, math.pi)  # facing the nadir
        world.step(0.3, command=cmd)  # frames captured before the teleport are still in flight
        frames = world.run(seconds)
        with_ball = sum(ball_near(f, ball) for f in frames)
        robot_there = sum(1 for f in frames
                          if robot_key in f.robots() and math.hypot(f.robots()[robot_key][0] - x,
                                                                     f.robots()[robot_key][1] - y) < 0.02)
        out[name] = {"frames": len(frames), "with_ball": with_ball, "robot_there": robot_there,
                     "robot_at": (x, y)}
    return out


def measure_radio(world, trials):
    """Command and response loss. Each trial: every robot is put back where the world file has it
    (at rest), and given one command, forward at 1 m/s (blue in the synchronous request, yellow on
    the yellow UDP port just before it); 0.3 s later a robot that moved more than 1 cm got it,
    one that did not lost it (the drive brakes after 0.1 s without a command, so it never moves
    on its own). The responses' RobotFeedback entries count the lost feedback: the blue response
    reports the request's last step, the yellow one the step before the request — each a draw of
    its own."""
    placed = world.placements()
    out = {"commands": 0, "arrived": 0, "unseen": 0, "feedback_expected": 0, "feedback_received": 0,
           "displacements": []}
    blue = sorted(k[1] for k in placed if k[0] == "blue")
    yellow = sorted(k[1] for k in placed if k[0] == "yellow")
    for _ in range(trials):
        home = control_pb.SimulatorCommand()
        for (team, rid), (x, y, yaw) in placed.items():
            sslsim.teleport_robot(home, common_pb.BLUE if team == "blue" else common_pb.YELLOW, rid, x, y, yaw)
        rc_yellow = robot_pb.RobotControl()
        for rid in yellow:
            sslsim.move_local(rc_yellow, rid, forward=1.0)
        rc_blue = robot_pb.RobotControl()
        for rid in blue:
            sslsim.move_local(rc_blue, rid, forward=1.0)
        # The yellow commands first (posted when the answer comes), the teleports and blue
        # commands with the request: all apply at the request's first step.
        ry = world.yellow_control(rc_yellow)
        response, frames = world.step(0.3, command=home, rc=rc_blue)
        assert not sslsim.codes(ry) and not response.robot_control_response.errors, (ry, response)
        out["feedback_expected"] += len(yellow) + len(blue)
        out["feedback_received"] += len(ry.feedback) + len(response.robot_control_response.feedback)
        # Where each robot came to rest: the frames sent in the request's last 30 ms.
        newest = max(f.t_sent for f in frames)
        final = {}
        for f in frames:
            if f.t_sent >= newest - 0.03:
                for key, pose in f.robots().items():
                    final.setdefault(key, []).append(pose)
        for key, (x, y, _) in placed.items():
            out["commands"] += 1
            if key not in final:
                out["unseen"] += 1
                continue
            fx = statistics.fmean(p[0] for p in final[key])
            fy = statistics.fmean(p[1] for p in final[key])
            moved = math.hypot(fx - x, fy - y)
            out["displacements"].append(moved)
            out["arrived"] += moved > 0.01
    return out


def geometry_cameras(world):
    """{camera_id: (x, y, z) mm} from the newest geometry packet received."""
    g = world.geometry()
    return {c.camera_id: (c.derived_camera_world_tx, c.derived_camera_world_ty, c.derived_camera_world_tz)
            for c in g.calib}


def expected_cameras(world_data, error):
    """{camera_id: (x, y, z) mm}: the grid's cameras (one row over the carpet, 6 m up: div-a and
    div-b) moved by `error` m along (0.3, 0.7, 0.05)."""
    import yaml
    with open(world_data["field"], encoding="utf-8") as f:
        field = yaml.safe_load(f)
    perception = world_data.get("perception", {})
    count = perception.get("camera_count", 1)
    height = perception.get("camera_height", 6.0)
    length = carpet_length(field)
    norm = math.sqrt(sum(c * c for c in CAMERA_ERROR_DIRECTION))
    dx, dy, dz = (error * c / norm for c in CAMERA_ERROR_DIRECTION)
    out = {}
    for i in range(count):
        x = -0.5 * length + length * (i + 0.5) / count
        out[i] = ((x + dx) * 1000.0, dy * 1000.0, (height + dz) * 1000.0)
    return out


def carpet_length(field):
    """The carpet's length from a field model file: the field and the run-off behind both goal lines
    (`goal_line_boundary_width`, else `boundary_width`)."""
    return field["field_length"] + 2.0 * field.get("goal_line_boundary_width", field["boundary_width"])


def measure_two_cameras(world, seconds):
    """div-a: two cameras over the halves. The ball at the centre is in both cameras' parts: each
    reports it shifted by object_position_offset from the field's centre towards itself. Returns
    {camera: (mean x − true x, mean y − true y, frames with the ball)} in m, and the reported
    camera positions."""
    world.run(0.5)
    frames = world.run(seconds)
    bx, by = world.ball_start()
    seen = {}
    for f in frames:
        for b in f.balls():
            if math.hypot(b[0] - bx, b[1] - by) < NEAR:
                seen.setdefault(f.wire.camera_id, []).append(b)
    out = {"ball": {c: (statistics.fmean(b[0] for b in v) - bx, statistics.fmean(b[1] for b in v) - by, len(v))
                    for c, v in seen.items()},
           "frames": {c: sum(f.wire.camera_id == c for f in frames) for c in sorted(seen)},
           "cameras": geometry_cameras(world)}
    return out


class RealTimeWorld(_Session):
    """`ubersim run COPY --realism PRESET --local-only` in real time (no synchronous mode): the
    datagrams' arrival against the wall clock."""

    def __init__(self, preset, world="div-b"):
        self.preset = preset
        self.vision_port, self.control_port, blue, yellow = harness.free_udp_ports(4)
        self.world = league_world(world, self.vision_port, (self.control_port, blue, yellow))
        self.receiver = harness.MulticastReceiver(self.vision_port)
        self.sim = harness.Simulator(self.world, extra_args=["--realism", preset])
        self.client = None
        self.received = []  # (Unix arrival time, SSL_DetectionFrame)

    def start(self):
        try:
            self.sim.start()
            self.client = harness.UdpClient()
            self.next_detection(30.0)
        except BaseException:
            self.close()
            raise
        return self

    def _sockets(self):
        return (self.client,)

    def next_detection(self, timeout=10.0):
        """The next detection frame: (Unix arrival time, SSL_DetectionFrame)."""
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                self.sim.assert_running()
                raise AssertionError("no detection frame within %s s" % timeout)
            data = self.receiver.recv(left)
            arrival = time.time()
            if data is None:
                continue
            p = parse(data)
            if p.HasField("detection"):
                self.received.append((arrival, p.detection))
                return arrival, p.detection

    def control(self, command):
        """A SimulatorCommand over UDP; its error codes (waits for the answer)."""
        self.client.send(command, self.control_port)
        reply = self.client.recv(10.0)
        assert reply is not None, "no SimulatorResponse:\n" + self.sim.output()
        r = control_pb.SimulatorResponse()
        r.ParseFromString(reply[0])
        return [e.code for e in r.errors]

    def detections(self, count, timeout=30.0):
        return [self.next_detection(timeout) for _ in range(count)]


def measure_arrival(world, frames=100, teleports=6):
    """In real time: (1) each frame's arrival (Unix time at the receiver) against its t_capture and
    t_sent; (2) the end-to-end latency: the ball teleported by a SimulatorCommand sent at W0, seen at
    its new spot in a frame arriving at W1.

    W1 − W0 is at least the vision delay while the simulator keeps to its schedule: a frame leaves
    no earlier than vision_delay of simulated time after a capture that follows the command, and
    the simulator never runs ahead of the wall clock. It may run behind (a busy machine) and then
    catch up to 100 ms in a burst, which shortens W1 − W0 by the lag it had at W0. The lag shows in
    the stamps: arrival − t_sent grows by it (from its smallest value in the run, when the
    simulator was on time). So the bound asserted is W1 − W0 + lag ≥ vision_delay."""
    out = {}
    got = world.detections(frames)
    out["arrival_minus_capture"] = [a - d.t_capture for a, d in got]
    out["arrival_minus_sent"] = [a - d.t_sent for a, d in got]
    spots = [(0.5, -0.5), (-0.5, -0.5)]
    trials = []
    for i in range(teleports):
        spot = spots[i % 2]
        cmd = teleport_ball(*spot)
        world.client.send(cmd, world.control_port)
        w0 = time.time()
        mark = len(world.received)
        while True:
            arrival, d = world.next_detection()
            if any(math.hypot(b.x / 1000.0 - spot[0], b.y / 1000.0 - spot[1]) < NEAR for b in d.balls):
                break
        reply = world.client.recv(10.0)
        assert reply is not None, "no SimulatorResponse"
        window = [a - d.t_sent for a, d in world.received[mark - 3:]]
        trials.append({"w1_minus_w0": arrival - w0, "lag_window": max(window)})
        world.detections(5)  # a pause between teleports, at another phase
    g_min = min(a - d.t_sent for a, d in world.received)
    for t in trials:
        t["lag"] = max(0.0, t["lag_window"] - g_min)
    out["trials"] = trials
    out["sent_minus_arrival_min"] = g_min
    return out


def measure_switch(world, frames=150):
    """A running world (real time) switched by a client's RealismConfigErForce from None to RC2021:
    the detrended σ of the robots' positions and the ball's before and after, and the stamps."""

    def sigmas(got):
        series, ball = {}, []
        for _, d in got:
            for team, robots in (("blue", d.robots_blue), ("yellow", d.robots_yellow)):
                for r in robots:
                    series.setdefault((team, r.robot_id), []).append((d.t_capture, r.x / 1000.0, r.y / 1000.0))
            ball += [(d.t_capture, b.x / 1000.0, b.y / 1000.0, b.area) for b in d.balls
                     if math.hypot(b.x, b.y) < NEAR * 1000]
        robot = detrended_sigma([[(p[0], p[1]) for p in v] for v in series.values()] +
                                [[(p[0], p[2]) for p in v] for v in series.values()])[0]
        ball_sigma = detrended_sigma([[(p[0], p[1]) for p in ball], [(p[0], p[2]) for p in ball]])[0]
        return {"robot_sigma": robot, "ball_sigma": ball_sigma, "ball_areas": len({p[3] for p in ball}),
                "processing": sorted({round(d.t_sent - d.t_capture, 4) for _, d in got})}

    world.detections(30)  # the robots settle
    before = sigmas(world.detections(frames))
    codes = world.control(realism_any(LEAGUE_PRESETS["RC2021"]))
    # Frames captured before the switch are still in flight: from the first one stamped with
    # RC2021's processing time on, every frame is captured under the new settings.
    target = LEAGUE_PRESETS["RC2021"]["vision_processing_time"] * 1e-9
    deadline = time.monotonic() + 30.0
    while True:
        assert time.monotonic() < deadline, "no frame with the new processing time"
        _, d = world.next_detection()
        if abs(d.t_sent - d.t_capture - target) < 1e-4:
            break
    after = sigmas(world.detections(frames))
    return {"codes": codes, "before": before, "after": after}
