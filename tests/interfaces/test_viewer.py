# SPDX-License-Identifier: Apache-2.0
"""The viewer end to end, in a real browser: Debian's Chromium, driven by its chromedriver through
Selenium, against `ubersim run` with the `viewer` transport (and `ssl_vision` beside it).

What the page drew is compared with the simulator's own state, read independently from ideal
SSL-Vision packets (preset `ideal`: no noise, no drop-outs, no latency, 60 Hz; `timestamps: sim`
makes t_capture the simulated time of the frame). The ball is dragged with real pointer input
(W3C actions in viewport coordinates), the world is paused and resumed with the page's button,
and a screenshot is saved (to $UBERSIM_TEST_OUTPUT_DIR, or a temporary folder; the path is
printed). The match: a Referee message sent as the game controller sends it (multicast on
loopback, to the viewer's referee_port) shows in the scoreboard, with the placement target on
the field. A replay: `ubersim replay LOG --viewer` on a log `ubersim run --record` wrote shows its
time slider, which seeks, and its controls, which reach the replay.

Without Chromium, chromedriver or Selenium the test is skipped, saying what is missing
(`./setup.sh` installs them).
"""
import contextlib
import math
import os
import re
import shutil
import signal
import socket
import struct
import subprocess
import tempfile
import threading
import time
import unittest
from unittest import mock

import harness
import ssl_gc_common_pb2 as gc_common_pb
import ssl_gc_game_event_pb2 as game_event_pb
import ssl_gc_referee_message_pb2 as referee_pb
import ssl_simulation_custom_ubersim_pb2 as ubersim_pb
import ssl_simulation_robot_control_pb2 as robot_pb
import ssl_simulation_robot_feedback_pb2 as feedback_pb
import ssl_vision_wrapper_pb2 as wrapper_pb2

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"

try:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common import service as selenium_service
    from selenium.webdriver.common.actions.action_builder import ActionBuilder
    from selenium.webdriver.common.by import By
    SELENIUM_ERROR = None
except ImportError as e:  # python3-selenium missing (or broken)
    SELENIUM_ERROR = e

# The page's colours (viewer.js): ball fill, team fills.
BALL_RGB = (0xff, 0x8a, 0x1f)
TEAM_RGB = {"blue": (0x2c, 0x6c, 0xff), "yellow": (0xff, 0xd5, 0x1c)}

REFEREE_GROUP = "224.5.23.1"
VISION_FRAME_RATE = 60.0   # Hz, preset ideal
STEP = 0.005               # s, the div-b world's physics step (the fast profile)
ENDPOINT_RE = re.compile(r"(http://127\.0\.0\.1:(\d+)/) \(open it in a browser\)")

STATE_JS = """
const v = window.ubersimViewer;
if (!v) return null;
const s = v.state;
return {connected: v.connected, frames: v.frames, drawn: v.drawn, world: v.hello ? v.hello.world : null,
        t: s ? s.t : null, ball: s ? s.ball : null, status: s ? s.status : null};
"""
# The robot panel's rows as [name, value] pairs.
PANEL_ROWS_JS = """
return Array.from(document.querySelectorAll('#robot-panel-rows tr'))
  .map((r) => [r.cells[0].textContent, r.cells[1].textContent]);
"""
TO_CLIENT_JS = "return window.ubersimViewer.fieldToClient(arguments[0], arguments[1]);"
TO_FIELD_JS = "return window.ubersimViewer.clientToField(arguments[0], arguments[1]);"
RECT_JS = """
const b = document.getElementById('field').getBoundingClientRect();
return {left: b.left, top: b.top, right: b.right, bottom: b.bottom, width: b.width, height: b.height,
        inner_width: window.innerWidth, inner_height: window.innerHeight, dpr: window.devicePixelRatio};
"""
# The canvas pixel under a client point, as the page last drew it (RGBA).
PIXEL_JS = """
const c = document.getElementById('field'), b = c.getBoundingClientRect();
const x = Math.floor((arguments[0] - b.left) * c.width / b.width);
const y = Math.floor((arguments[1] - b.top) * c.height / b.height);
return Array.from(c.getContext('2d').getImageData(x, y, 1, 1).data);
"""


def text_of(driver, element_id):
    return driver.find_element(By.ID, element_id).text


def parse(data):
    packet = wrapper_pb2.SSL_WrapperPacket()
    packet.ParseFromString(data)
    return packet


def close_colour(rgba, rgb, tolerance=40):
    return rgba[3] == 255 and all(abs(a - b) <= tolerance for a, b in zip(rgba, rgb))


class VisionWatcher:
    """Receives the SSL-Vision packets on a thread of its own (a socket left unread for a while
    would overflow and drop the newest), keeping every detection frame with its arrival time."""

    def __init__(self, receiver):
        self.receiver = receiver
        self.lock = threading.Lock()
        self.detections = []   # (monotonic arrival, SSL_DetectionFrame)
        self.geometry_packets = 0
        self.errors = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="vision", daemon=True)
        self._thread.start()

    def _run(self):
        while not self._stop.is_set():
            data = self.receiver.recv(0.05)
            if data is None:
                continue
            arrival = time.monotonic()
            try:
                packet = parse(data)
            except Exception as e:  # noqa: BLE001 (kept for the test to report)
                with self.lock:
                    self.errors.append(repr(e))
                continue
            with self.lock:
                if packet.HasField("detection"):
                    self.detections.append((arrival, packet.detection))
                if packet.HasField("geometry"):
                    self.geometry_packets += 1

    def count(self):
        with self.lock:
            return len(self.detections)

    def since(self, index):
        with self.lock:
            return [d for _, d in self.detections[index:]]

    def latest(self):
        with self.lock:
            return self.detections[-1][1] if self.detections else None

    def nearest(self, t):
        """The detection frame whose t_capture is nearest to sim time t (None before any)."""
        with self.lock:
            frames = [d for _, d in self.detections[-600:]]
        return min(frames, key=lambda d: abs(d.t_capture - t)) if frames else None

    def stop(self):
        self._stop.set()
        self._thread.join(timeout=5)


def robots_of(detection):
    """{(team, id): (x m, y m, yaw rad)} of one detection frame (the packets are in mm)."""
    out = {}
    for team, robots in (("blue", detection.robots_blue), ("yellow", detection.robots_yellow)):
        for r in robots:
            out[(team, r.robot_id)] = (r.x / 1000.0, r.y / 1000.0, r.orientation)
    return out


def angle_difference(a, b):
    return abs(math.atan2(math.sin(a - b), math.cos(a - b)))


def browser_missing():
    """Why the browser cannot be driven here, or None."""
    missing = []
    if not (os.path.isfile(CHROMIUM) and os.access(CHROMIUM, os.X_OK)):
        missing.append(f"Chromium ({CHROMIUM}, Debian package chromium)")
    if not (os.path.isfile(CHROMEDRIVER) and os.access(CHROMEDRIVER, os.X_OK)):
        missing.append(f"chromedriver ({CHROMEDRIVER}, Debian package chromium-driver)")
    if SELENIUM_ERROR is not None:
        missing.append(f"Selenium for /usr/bin/python3 (Debian package python3-selenium: {SELENIUM_ERROR})")
    if not missing:
        return None
    return "the viewer's browser test needs " + " and ".join(missing) + "; ./setup.sh installs them"


def start_chromium(workdir, driver_log):
    """Headless Chromium through its chromedriver, its profile in `workdir`."""
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--no-first-run", "--disable-background-networking", "--disable-component-update",
                "--disable-sync", "--window-size=1280,900",
                "--user-data-dir=" + os.path.join(workdir, "profile")):
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    service = Service(executable_path=CHROMEDRIVER, log_path=driver_log)

    # Selenium Manager (which downloads drivers) is only tried when the driver cannot be
    # started from its path; with an explicit chromedriver it must never run: make it fail.
    class NoSeleniumManager:
        def __init__(self, *args, **kwargs):
            raise AssertionError("Selenium tried to run Selenium Manager (a download)")

    with mock.patch.object(selenium_service, "SeleniumManager", NoSeleniumManager):
        driver = webdriver.Chrome(service=service, options=options)
    driver.set_page_load_timeout(30)
    driver.set_script_timeout(10)
    return driver


def output_directory():
    path = os.environ.get("UBERSIM_TEST_OUTPUT_DIR")
    if path:
        os.makedirs(path, exist_ok=True)
        return path
    return tempfile.mkdtemp(prefix="ubersim_test_viewer_")


class ViewerInBrowser(unittest.TestCase):
    """Div B (12 robots) in real time, one browser on the viewer. The tests share the simulator
    and the page and run in the order of their names."""

    sim = None
    driver = None
    vision = None

    @classmethod
    def setUpClass(cls):
        reason = browser_missing()
        if reason:
            raise unittest.SkipTest(reason)
        cls.console = []
        cls.workdir = tempfile.mkdtemp(prefix="ubersim_viewer_browser_")
        cls.addClassCleanup(shutil.rmtree, cls.workdir, ignore_errors=True)
        cls.started = time.monotonic()

        vision_port, control_port, cls.blue_port, yellow_port, cls.referee_port = harness.free_udp_ports(5)
        receiver = harness.MulticastReceiver(vision_port)
        cls.addClassCleanup(receiver.close)
        cls.world = harness.World("div-b")
        # The referee on a port of the test's own: nothing else on this machine publishes there.
        cls.world.add_transport("viewer", port=0, referee_port=cls.referee_port)
        cls.world.add_transport("ssl_vision", port=vision_port, interface=harness.LOOPBACK, timestamps="sim")
        # A team's software beside the page: commands for a robot the page then shows.
        cls.world.add_transport("ssl_simulation", control_port=control_port, blue_port=cls.blue_port,
                                yellow_port=yellow_port)
        cls.world.set_perception(preset="ideal")  # 60 Hz, latency 0, no noise, no drop-outs
        cls.vision = VisionWatcher(receiver)
        cls.addClassCleanup(cls.vision.stop)  # runs before receiver.close (cleanups are LIFO)

        cls.sim = harness.Simulator(cls.world)
        cls.addClassCleanup(cls.sim.close)
        cls.sim.start()
        with cls.diagnosed():
            match = harness.wait_for(lambda: cls.sim.assert_running() or ENDPOINT_RE.search(cls.sim.output()),
                                     20.0, interval=0.05, what="the viewer's address in ubersim's log")
            cls.url = match.group(1)
            harness.wait_for(cls.vision.latest, 20.0, what="a first SSL-Vision detection packet")
            cls.driver = cls.start_browser()
            cls.addClassCleanup(cls.quit_browser)
            cls.driver.get(cls.url)
            cls.page = harness.wait_for(cls.ready_page, 30.0, interval=0.05,
                                        what="the page connected, drawing 12 robots")
            print(f"\nviewer at {cls.url}; page ready {time.monotonic() - cls.started:.1f} s after start")

    @classmethod
    def start_browser(cls):
        cls.driver_log = os.path.join(cls.workdir, "chromedriver.log")
        return start_chromium(cls.workdir, cls.driver_log)

    @classmethod
    def quit_browser(cls):
        if cls.driver is not None:
            cls.collect_console()
            cls.driver.quit()
            cls.driver = None

    @classmethod
    def collect_console(cls):
        if cls.driver is None:
            return
        try:
            cls.console += cls.driver.get_log("browser")
        except Exception as e:  # noqa: BLE001 (a log is a bonus; never hide the real failure)
            cls.console.append({"level": "INFO", "message": f"(browser log unavailable: {e!r})"})

    @classmethod
    def diagnostics(cls):
        cls.collect_console()
        console = "\n".join(f"  {e.get('level')}: {e.get('message')}" for e in cls.console) or "  (empty)"
        parts = ["--- ubersim log ---", cls.sim.output() if cls.sim else "(not started)",
                 "--- browser console ---", console]
        log = getattr(cls, "driver_log", None)
        if log and os.path.exists(log) and cls.driver is None:
            with open(log, encoding="utf-8", errors="replace") as f:
                parts += ["--- chromedriver log (tail) ---", f.read()[-3000:]]
        return "\n".join(parts)

    @classmethod
    @contextlib.contextmanager
    def diagnosed(cls):
        """Re-raises a failure with the simulator's log and the browser's console appended."""
        try:
            yield
        except unittest.SkipTest:
            raise
        except AssertionError as e:
            raise AssertionError(f"{e}\n{cls.diagnostics()}") from e
        except Exception as e:  # noqa: BLE001 (WebDriverException, timeouts, ...)
            raise AssertionError(f"{type(e).__name__}: {e}\n{cls.diagnostics()}") from e

    # ------------------------------------------------------------------ page helpers

    @classmethod
    def state(cls):
        return cls.driver.execute_script(STATE_JS)

    @classmethod
    def ready_page(cls):
        cls.sim.assert_running()
        s = cls.state()
        if s and s["connected"] and s["drawn"] and len(s["drawn"]["robots"]) == 12 and s["drawn"]["ball"]:
            return s
        return None

    def to_client(self, x, y):
        p = self.driver.execute_script(TO_CLIENT_JS, x, y)
        return p["x"], p["y"]

    def to_field(self, cx, cy):
        p = self.driver.execute_script(TO_FIELD_JS, cx, cy)
        return p["x"], p["y"]

    def pixel(self, cx, cy):
        return self.driver.execute_script(PIXEL_JS, cx, cy)

    def scale(self):
        """CSS px per metre, from fieldToClient of two points (and the y flip checked)."""
        x0, y0 = self.to_client(0.0, 0.0)
        x1, y1 = self.to_client(1.0, 1.0)
        self.assertGreater(x1 - x0, 10.0, "field +x goes right on the screen")
        self.assertAlmostEqual(y0 - y1, x1 - x0, delta=1e-6, msg="uniform scale, field +y goes up")
        return x1 - x0

    def wait_ball_at(self, x, y, tolerance, timeout, what):
        """The first detection frame that shows the ball within `tolerance` m of (x, y)."""
        def found():
            self.sim.assert_running()
            d = self.vision.latest()
            if d is not None and len(d.balls) == 1:
                b = d.balls[0]
                if math.hypot(b.x / 1000.0 - x, b.y / 1000.0 - y) <= tolerance:
                    return d
            return None
        try:
            return harness.wait_for(found, timeout, what=what)
        except AssertionError as e:
            d = self.vision.latest()
            balls = [(b.x / 1000.0, b.y / 1000.0) for b in d.balls] if d else None
            raise AssertionError(f"{e}: expected ({x:.4f}, {y:.4f}) m ± {tolerance} m, the last frame "
                                 f"(t_capture {d.t_capture if d else None}) has the ball at {balls}") from e

    # ------------------------------------------------------------------ tests

    def test_1_robots_drawn_where_the_simulator_has_them(self):
        with self.diagnosed():
            self.assertEqual(self.page["world"], "div-b")
            rect = self.driver.execute_script(RECT_JS)
            self.assertGreater(rect["width"], 600)
            self.assertGreater(rect["height"], 300)
            px_per_m = self.scale()
            # The robots stand still at kick-off; the drawn state is compared with the vision
            # frame captured nearest to its sim time (frames every 1/60 s, ideal: latency 0).
            page = self.state()
            drawn = page["drawn"]
            t = drawn["t"]
            self.assertIsNotNone(t)
            detection = harness.wait_for(
                lambda: self.vision.latest() is not None and self.vision.latest().t_capture >= t
                and self.vision.nearest(t), 10.0, what=f"a vision frame captured at or after t = {t} s")
            self.assertLessEqual(abs(detection.t_capture - t), 1.0 / VISION_FRAME_RATE + 1e-6,
                                 "vision frames every 1/60 s of sim time")
            self.assertEqual(detection.t_sent, detection.t_capture, "preset ideal: no latency")
            truth = robots_of(detection)
            placed = {(r["team"], r["id"]): (r["x"], r["y"]) for r in self.world.robots()}
            self.assertEqual(len(drawn["robots"]), 12)
            drawn_keys = [(r["team"], r["id"]) for r in drawn["robots"]]
            self.assertEqual(sorted(drawn_keys), sorted(placed), "each robot drawn once")
            self.assertEqual(sorted(truth), sorted(placed), "ideal vision sees every robot")
            worst = 0.0
            for r in drawn["robots"]:
                key = (r["team"], r["id"])
                tx, ty, tyaw = truth[key]
                # The vision truth is where the world file puts the robot (checks units and axes
                # of the reference itself: 5 mm is far below any mix-up of mm, m or a sign).
                self.assertAlmostEqual(tx, placed[key][0], delta=0.005, msg=f"{key} vision x")
                self.assertAlmostEqual(ty, placed[key][1], delta=0.005, msg=f"{key} vision y")
                # 2 mm: the state message rounds to 0.1 mm, the packets are float mm (~0.001 mm
                # here), and a robot at rest settles a fraction of a mm in the first moments, of
                # which at most 1/60 s separates the two samples. A robot drawn one pixel off
                # (~8 mm at this size), swapped or mirrored fails.
                error = math.hypot(r["x"] - tx, r["y"] - ty)
                worst = max(worst, error)
                self.assertLess(error, 0.002, f"{key}: drawn at ({r['x']}, {r['y']}), simulator has ({tx}, {ty})")
                self.assertLess(angle_difference(r["yaw"], tyaw), 0.005, f"{key} yaw")
                # The screen point is the field point through the page's own transform, inside
                # the canvas, and the canvas really shows the team's colour there (to one side of
                # the centre, clear of the id drawn on it).
                cx, cy = self.to_client(r["x"], r["y"])
                self.assertAlmostEqual(r["cx"], cx, delta=0.01, msg=f"{key} cx")
                self.assertAlmostEqual(r["cy"], cy, delta=0.01, msg=f"{key} cy")
                self.assertTrue(rect["left"] < cx < rect["right"] and rect["top"] < cy < rect["bottom"],
                                f"{key} at ({cx}, {cy}) outside the canvas {rect}")
                side = self.pixel(cx, cy + 0.65 * 0.09 * px_per_m)
                self.assertTrue(close_colour(side, TEAM_RGB[key[0]]), f"{key}: canvas shows {side}")
            ball = drawn["ball"]
            self.assertAlmostEqual(ball["x"], 0.0, delta=0.002)
            self.assertAlmostEqual(ball["y"], 0.0, delta=0.002)
            print(f"\nrobots: worst drawn-vs-vision error {worst * 1000:.3f} mm at t = {t:.3f} s "
                  f"(frame at {detection.t_capture:.3f} s); {px_per_m:.1f} px/m")

    def test_2_dragging_the_ball_moves_it_in_the_simulator(self):
        with self.diagnosed():
            px_per_m = self.scale()
            one_px = 1.0 / px_per_m
            rect = self.driver.execute_script(RECT_JS)
            page = harness.wait_for(lambda: (lambda s: s if s["drawn"]["ball"] else None)(self.state()),
                                    5.0, what="the ball drawn")
            ball = page["drawn"]["ball"]
            self.assertLess(math.hypot(ball["x"], ball["y"]), 0.002, "the ball starts at the centre spot")
            start = (round(ball["cx"]), round(ball["cy"]))
            self.assertTrue(close_colour(self.pixel(ball["cx"], ball["cy"]), BALL_RGB), "ball drawn in orange")

            # The pointer path: integer viewport pixels towards field (1.0, -0.8), halfway first.
            target_field = (1.0, -0.8)
            tx, ty = self.to_client(*target_field)
            target = (round(tx), round(ty))
            self.assertTrue(rect["left"] < target[0] < rect["right"] and rect["top"] < target[1] < rect["bottom"])
            steps = 8
            path = [(round(start[0] + (target[0] - start[0]) * i / steps),
                     round(start[1] + (target[1] - start[1]) * i / steps)) for i in range(1, steps + 1)]
            halfway = path[steps // 2 - 1]
            # Where the page will put the ball: its own inverse of each pointer position.
            halfway_field = self.to_field(*halfway)
            drop_field = self.to_field(*target)
            # Rounding the pointer to whole pixels moves it by at most half a pixel on each axis.
            self.assertLess(math.hypot(drop_field[0] - target_field[0], drop_field[1] - target_field[1]), one_px)

            # Press on the ball, move halfway, hold still a moment, move on to the target and
            # release: one action sequence (chromedriver ends the pointer capture between two).
            mark = self.vision.count()
            actions = ActionBuilder(self.driver, duration=40)
            actions.pointer_action.move_to_location(*start)
            actions.pointer_action.pointer_down()
            for p in path[:steps // 2]:
                actions.pointer_action.move_to_location(*p)
            actions.pointer_action.pause(0.5)
            for p in path[steps // 2:]:
                actions.pointer_action.move_to_location(*p)
            actions.pointer_action.pointer_up()
            actions.perform()

            # The simulator (ideal vision: the truth) has the ball at the drop point: within one
            # CSS pixel (the pointer's resolution) and 2 mm of field (1.0, -0.8), and within
            # 1 mm of the page's exact drop point (the move is rounded to 0.1 mm; the ball is
            # placed at rest on the carpet and stays).
            arrived = self.wait_ball_at(*drop_field, 0.001, 10.0, "the ball at the drop point in the simulator")
            b = arrived.balls[0]
            bx, by = b.x / 1000.0, b.y / 1000.0
            self.assertLess(math.hypot(bx - target_field[0], by - target_field[1]), one_px + 0.002)
            # On the way the ball followed the pointer while the button was held: every position
            # the cameras saw lies on the pointer's line (within a pixel), in order, and the
            # ball stood at the halfway point while the pointer rested there.
            s0 = self.to_field(*start)
            ux, uy = drop_field[0] - s0[0], drop_field[1] - s0[1]
            length = math.hypot(ux, uy)
            ux, uy = ux / length, uy / length
            along, held = [], 0
            for d in self.vision.since(mark):
                self.assertEqual(len(d.balls), 1, "ideal vision always sees the ball")
                px, py = d.balls[0].x / 1000.0 - s0[0], d.balls[0].y / 1000.0 - s0[1]
                self.assertLess(abs(px * uy - py * ux), one_px + 0.001,
                                f"ball at ({d.balls[0].x:.1f}, {d.balls[0].y:.1f}) mm off the drag line")
                along.append(px * ux + py * uy)
                if math.hypot(d.balls[0].x / 1000.0 - halfway_field[0], d.balls[0].y / 1000.0 - halfway_field[1]) < 0.001:
                    held += 1
            self.assertGreaterEqual(held, 1, "frames with the ball at the halfway point")
            self.assertTrue(all(b >= a - 0.001 for a, b in zip(along, along[1:])), f"in order: {along}")
            # It stays there (placed at rest): half a second of sim time later, still there.
            later = harness.wait_for(lambda: (lambda d: d if d and d.t_capture >= arrived.t_capture + 0.5 else None)(
                self.vision.latest()), 10.0, what="vision 0.5 s after the drop")
            self.assertEqual(len(later.balls), 1)
            self.assertLess(math.hypot(later.balls[0].x / 1000.0 - bx, later.balls[0].y / 1000.0 - by), 0.001)

            # The page draws it there from the simulator's state (past the page's 0.5 s hold of
            # the drop point): the state's ball and the drawn ball, on screen too.
            def drawn_from_state():
                s = self.state()
                if s["t"] is None or s["t"] < later.t_capture or not s["drawn"]["ball"]:
                    return None
                return s
            page = harness.wait_for(drawn_from_state, 10.0, what="the page showing the state after the drop")
            drawn = page["drawn"]["ball"]
            self.assertLess(math.hypot(page["ball"]["x"] - bx, page["ball"]["y"] - by), 0.001, "state ball")
            self.assertLess(math.hypot(drawn["x"] - bx, drawn["y"] - by), 0.001, "drawn ball")
            self.assertAlmostEqual(drawn["z"], 0.0215, delta=0.001, msg="lying on the carpet")
            cx, cy = self.to_client(drawn["x"], drawn["y"])
            self.assertAlmostEqual(drawn["cx"], cx, delta=0.01)
            self.assertAlmostEqual(drawn["cy"], cy, delta=0.01)
            self.assertLessEqual(math.hypot(cx - target[0], cy - target[1]), 1.0, "drawn under the drop point")
            self.assertTrue(close_colour(self.pixel(cx, cy), BALL_RGB), "ball drawn at the drop point")
            old = self.pixel(*self.to_client(0.0, 0.0))
            self.assertFalse(close_colour(old, BALL_RGB), f"no ball left at the centre spot: {old}")
            print(f"\nball dropped at ({bx:.4f}, {by:.4f}) m for target {target_field}; "
                  f"one pixel = {one_px * 1000:.2f} mm")

    def resume_if_paused(self):
        """Cleanup: a test that failed while paused leaves the world running for the next."""
        if self.driver is not None and text_of(self.driver, "pause") == "Resume":
            self.driver.execute_script("window.ubersimViewer.send({cmd: 'resume'});")

    def test_3_pause_button_stops_sim_time_and_resume_restarts_it(self):
        self.addCleanup(self.resume_if_paused)
        with self.diagnosed():
            page = self.state()
            self.assertEqual(text_of(self.driver, "run-state"), "running")
            self.assertFalse(page["status"]["paused"])
            self.assertEqual(text_of(self.driver, "pause"), "Pause")
            self.driver.find_element(By.ID, "pause").click()
            # The server reports paused once sim time stood still for half a second.
            harness.wait_for(lambda: text_of(self.driver, "run-state") == "paused", 10.0,
                             what="#run-state 'paused'")
            self.assertEqual(text_of(self.driver, "pause"), "Resume")
            page = self.state()
            self.assertTrue(page["status"]["paused"])
            t0 = page["t"]
            self.assertEqual(text_of(self.driver, "sim-time"), f"{t0:.3f} s")
            # Sim time stands still for a second: the page's state, and no detection frame.
            mark = self.vision.count()
            last = self.vision.latest()
            times = []
            end = time.monotonic() + 1.0
            while time.monotonic() < end:  # the deliberate observation window
                times.append(self.state()["t"])
                time.sleep(0.1)
            after = self.vision.since(mark)
            self.sim.assert_running()
            self.assertGreaterEqual(len(times), 3)
            self.assertEqual(set(times), {t0}, "the page's sim time moved while paused")
            self.assertEqual([d.t_capture for d in after], [], "detection frames while paused")
            self.assertEqual(text_of(self.driver, "sim-time"), f"{t0:.3f} s")

            self.driver.find_element(By.ID, "pause").click()
            harness.wait_for(lambda: self.vision.count() > mark, 10.0, what="detection frames after resuming")
            harness.wait_for(lambda: (self.state()["t"] or 0) > t0 + 0.2, 10.0,
                             what="the page's sim time advancing after resuming")
            harness.wait_for(lambda: text_of(self.driver, "run-state") == "running", 10.0,
                             what="#run-state 'running'")
            self.assertEqual(text_of(self.driver, "pause"), "Pause")
            first = self.vision.since(mark)[0]
            # Vision picks up where it stopped: the next frame, one frame period (of sim time)
            # after the last one before the pause; the world paused at a time T in between.
            self.assertAlmostEqual(first.t_capture - last.t_capture, 1.0 / VISION_FRAME_RATE, delta=STEP + 1e-9,
                                   msg="frames across the pause")
            # The page's paused time t0 is the time the simulator stopped at, T: the viewer samples
            # the world `rate` times a wall-clock second, but when the world stops between two
            # samples it fetches the exact state at once. So last frame <= T < first frame.
            self.assertLess(t0, first.t_capture)
            # T may be the last frame's own step: equal times, which reach us by two roads (the
            # page's state in seconds, the frame's capture time from SSL-Vision's packet) and can
            # differ in the last bit (6.417 against 6.417000000000001): a microsecond's slack.
            self.assertGreaterEqual(t0 + 1e-6, last.t_capture, "the page's paused time lags the simulator")
            lag = last.t_capture - t0
            print(f"\npaused at t = {t0:.3f} s ({len(times)} samples); last frame before at "
                  f"{last.t_capture:.3f} s, first after at {first.t_capture:.3f} s"
                  + (f" (the page's paused time lags the simulator by >= {lag * 1000:.0f} ms)" if lag > 0 else ""))

    def test_4_screenshot(self):
        with self.diagnosed():
            harness.wait_for(lambda: text_of(self.driver, "run-state") == "running", 10.0, what="running")
            path = os.path.join(output_directory(), "viewer.png")
            if os.path.exists(path):
                os.remove(path)
            self.assertTrue(self.driver.save_screenshot(path))
            print(f"\nscreenshot: {path}")
            with open(path, "rb") as f:
                data = f.read()
            self.assertEqual(data[:8], b"\x89PNG\r\n\x1a\n")
            self.assertEqual(data[12:16], b"IHDR")
            width, height = struct.unpack(">II", data[16:24])
            rect = self.driver.execute_script(RECT_JS)
            self.assertEqual((width, height), (round(rect["inner_width"] * rect["dpr"]),
                                               round(rect["inner_height"] * rect["dpr"])))
            self.assertGreater(len(data), 20_000, "a drawn field, not a blank page")

    def test_5_clicking_a_robot_shows_what_its_drive_measures(self):
        with self.diagnosed():
            harness.wait_for(lambda: text_of(self.driver, "run-state") == "running", 10.0, what="running")
            self.assertFalse(self.driver.find_element(By.ID, "robot-panel").is_displayed())
            robot = harness.wait_for(
                lambda: next((r for r in self.state()["drawn"]["robots"] if r["team"] == "blue" and r["id"] == 1), None),
                5.0, what="blue 1 drawn")
            # A click (press and release without moving) on the robot opens its panel.
            actions = ActionBuilder(self.driver, duration=40)
            actions.pointer_action.move_to_location(round(robot["cx"]), round(robot["cy"]))
            actions.pointer_action.click()
            actions.perform()
            panel = self.driver.find_element(By.ID, "robot-panel")
            harness.wait_for(panel.is_displayed, 5.0, what="the robot panel shown")
            self.assertEqual(text_of(self.driver, "robot-panel-title"), "blue 1")

            # The team's software turns the robot on the spot at 3 rad/s, a command every 20 ms as
            # an AI sends them; the panel shows what the drive measures, as the robot's own
            # feedback (RobotFeedback.custom) does.
            rc = robot_pb.RobotControl()
            c = rc.robot_commands.add()
            c.id = 1
            v = c.move_command.local_velocity
            v.forward, v.left, v.angular = 0.0, 0.0, 3.0
            stop = threading.Event()
            replies, failures = [], []

            def command():
                try:
                    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
                        sock.settimeout(1.0)
                        while not stop.is_set():
                            sock.sendto(rc.SerializeToString(), (harness.LOOPBACK, self.blue_port))
                            with contextlib.suppress(socket.timeout):
                                reply = feedback_pb.RobotControlResponse()
                                reply.ParseFromString(sock.recv(65536))
                                replies.append(reply)
                            stop.wait(0.02)
                except Exception as e:  # noqa: BLE001 (reported by the test, not lost in a thread)
                    failures.append(repr(e))

            sender = threading.Thread(target=command, name="team-ai", daemon=True)
            sender.start()
            try:
                seen = {}

                def turning_in_panel():
                    self.sim.assert_running()
                    rows = dict(self.driver.execute_script(PANEL_ROWS_JS))
                    seen["rows"], seen["replies"] = rows, len(replies)
                    self.assertEqual(failures, [], "the team's client failed")
                    said = rows.get("drive says", "")  # "0.00 fwd, 0.00 left m/s · 3.00 rad/s"
                    match = re.search(r"([-0-9.]+) rad/s$", said)
                    return rows if match and abs(float(match.group(1)) - 3.0) < 0.15 else None
                try:
                    rows = harness.wait_for(turning_in_panel, 10.0, interval=0.1,
                                            what="the panel showing the drive turning at 3 rad/s")
                except AssertionError as e:
                    raise AssertionError(f"{e}; the panel last showed {seen.get('rows')}, "
                                         f"{seen.get('replies')} replies to the commands") from e
                truth = next(r for r in self.driver.execute_script("return window.ubersimViewer.state.robots")
                             if r["team"] == "blue" and r["id"] == 1)
            finally:
                stop.set()
                sender.join(timeout=5)

            # Four wheels, each at the speed the page received, all one sign (turning on the spot).
            wheels = [rows.get(f"wheel {i}") for i in range(1, 5)]
            self.assertTrue(all(wheels), rows)
            speeds = [float(w.split()[0]) for w in wheels]
            self.assertTrue(all(abs(v) > 3.0 * 0.079 / 0.029 * 0.8 for v in speeds), speeds)  # omega d / r
            self.assertTrue(all(v > 0 for v in speeds) or all(v < 0 for v in speeds), speeds)
            self.assertEqual(len(truth["drive"]["wheels"]), 4)
            self.assertAlmostEqual(truth["drive"]["angular"], truth["w"], delta=0.2,
                                   msg="the drive's own measure agrees with the truth")
            # The same measurements reached the team's software.
            self.assertTrue(replies, "no RobotControlResponse came back")
            drive = ubersim_pb.UberSimDriveFeedback()
            self.assertTrue(replies[-1].feedback[0].custom.Unpack(drive))
            self.assertAlmostEqual(drive.angular, 3.0, delta=0.15)

            # Clicking the carpet closes the panel.
            x, y = self.to_client(0.0, 2.5)
            actions = ActionBuilder(self.driver, duration=40)
            actions.pointer_action.move_to_location(round(x), round(y))
            actions.pointer_action.click()
            actions.perform()
            harness.wait_for(lambda: not panel.is_displayed(), 5.0, what="the panel closed")

    def send_referee_until(self, message, shown, what):
        """Sends `message` as the game controller does (multicast on loopback, every 0.1 s, as a
        datagram may be lost) until `shown(page's last referee message)` holds."""
        data = message.SerializeToString()
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, socket.inet_aton(harness.LOOPBACK))
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 1)
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)

            def arrived():
                self.sim.assert_running()
                sock.sendto(data, (REFEREE_GROUP, self.referee_port))
                ref = self.driver.execute_script("return window.ubersimViewer.referee")
                return ref if ref and shown(ref) else None
            return harness.wait_for(arrived, 10.0, interval=0.1, what=what)

    @staticmethod
    def referee_message(command, counter):
        """A second-half Referee message, ER-Force (yellow) 2 : 1 TIGERs (blue), blue on the
        positive half, a yellow card for yellow with 95 s left."""
        r = referee_pb.Referee()
        r.packet_timestamp = int(time.time() * 1e6)
        r.stage = referee_pb.Referee.NORMAL_SECOND_HALF
        r.stage_time_left = 125_400_000  # µs
        r.command = command
        r.command_counter = counter
        r.command_timestamp = r.packet_timestamp
        r.blue_team_on_positive_half = True
        for team, name, score in ((r.yellow, "ER-Force", 2), (r.blue, "TIGERs", 1)):
            team.name, team.score, team.red_cards, team.yellow_cards = name, score, 0, 0
            team.timeouts, team.timeout_time, team.goalkeeper, team.foul_counter = 4, 300_000_000, 0, 1
        r.yellow.yellow_cards = 1
        r.yellow.yellow_card_times.append(95_000_000)
        r.yellow.goalkeeper = 1
        return r

    def test_6_the_scoreboard_shows_the_referee(self):
        with self.diagnosed():
            # Listening, nothing heard yet: only the hint.
            hint = text_of(self.driver, "sb-hint")
            self.assertIn("no referee", hint)
            self.assertIn(f"{REFEREE_GROUP}:{self.referee_port}", hint)
            self.assertFalse(self.driver.find_element(By.ID, "sb-match").is_displayed())

            # A ball placement by blue to (2, -2) m, clear of every robot and the ball.
            target = (2.0, -2.0)
            page = self.state()
            for r in self.driver.execute_script("return window.ubersimViewer.state.robots"):
                self.assertGreater(math.hypot(r["x"] - target[0], r["y"] - target[1]), 0.4, f"{r} on the target")
            self.assertGreater(math.hypot(page["ball"]["x"] - target[0], page["ball"]["y"] - target[1]), 0.4)
            r = self.referee_message(referee_pb.Referee.BALL_PLACEMENT_BLUE, 7)
            r.next_command = referee_pb.Referee.DIRECT_FREE_BLUE
            r.current_action_time_remaining = 29_000_000
            r.designated_position.x, r.designated_position.y = target[0] * 1000, target[1] * 1000  # mm
            e = r.game_events.add()
            e.type = game_event_pb.GameEvent.BALL_LEFT_FIELD_TOUCH_LINE
            e.ball_left_field_touch_line.by_team = gc_common_pb.YELLOW
            e.ball_left_field_touch_line.by_bot = 3
            r.status_message = "Ball placement by blue"
            self.send_referee_until(r, lambda ref: ref["command_counter"] == 7, "the placement on the page")

            harness.wait_for(lambda: self.driver.find_element(By.ID, "sb-match").is_displayed(), 5.0,
                             what="the scoreboard shown")
            self.assertEqual(text_of(self.driver, "sb-hint"), "")
            # Yellow on the negative half: on the left.
            self.assertIn("ER-Force", text_of(self.driver, "sb-left"))
            self.assertIn("TIGERs", text_of(self.driver, "sb-right"))
            self.assertEqual(text_of(self.driver, "sb-score"), "2 : 1")
            self.assertEqual(text_of(self.driver, "sb-stage"), "2nd half")
            self.assertEqual(text_of(self.driver, "sb-clock"), "02:05")
            self.assertEqual(text_of(self.driver, "sb-command"), "Ball placement blue")
            self.assertEqual(text_of(self.driver, "sb-next"), "next: Free kick blue")
            self.assertEqual(text_of(self.driver, "sb-action"), "action 29.0 s")
            self.assertIn("1 (01:35)", text_of(self.driver, "sb-left"), "the yellow card's time left")
            self.assertEqual(text_of(self.driver, "sb-event"), "last event: Ball left field touch line · yellow 3")
            self.assertEqual(text_of(self.driver, "sb-status"), "Ball placement by blue")
            yellow = self.driver.find_element(By.CSS_SELECTOR, "#sb-left .sb-name.yellow")
            self.assertEqual(yellow.value_of_css_property("background-color"), "rgba(255, 213, 28, 1)")

            # The target on the field: where the page's transform puts (2, -2) m, in blue.
            drawn = harness.wait_for(lambda: self.state()["drawn"]["target"], 5.0, what="the target drawn")
            self.assertAlmostEqual(drawn["x"], target[0], delta=1e-6)
            self.assertAlmostEqual(drawn["y"], target[1], delta=1e-6)
            self.assertEqual(drawn["text"], "ball placement blue")
            cx, cy = self.to_client(*target)
            self.assertAlmostEqual(drawn["cx"], cx, delta=0.01)
            self.assertAlmostEqual(drawn["cy"], cy, delta=0.01)
            self.assertTrue(close_colour(self.pixel(cx, cy), TEAM_RGB["blue"]), f"target centre {self.pixel(cx, cy)}")
            path = os.path.join(output_directory(), "viewer-match.png")
            self.assertTrue(self.driver.save_screenshot(path))
            print(f"\nscoreboard: {text_of(self.driver, 'scoreboard')!r}; screenshot {path}")

            # Play resumes: no target, the event stays as the last one (dimmed).
            self.send_referee_until(self.referee_message(referee_pb.Referee.NORMAL_START, 8),
                                    lambda ref: ref["command_counter"] == 8, "the normal start on the page")
            harness.wait_for(lambda: self.state()["drawn"]["target"] is None, 5.0, what="the target gone")
            self.assertEqual(text_of(self.driver, "sb-command"), "Normal start")
            self.assertEqual(text_of(self.driver, "sb-next"), "")
            self.assertIn("old", self.driver.find_element(By.ID, "sb-event").get_attribute("class"))

    def test_9_no_errors_in_the_console(self):
        with self.diagnosed():
            self.collect_console()
            severe = [e for e in self.console if e.get("level") == "SEVERE"
                      and "favicon.ico" not in e.get("message", "")]
            self.assertEqual(severe, [])
            self.assertEqual(self.vision.errors, [], "undecodable vision packets")
            self.assertGreaterEqual(self.vision.geometry_packets, 1, "the geometry sent at start")
            self.sim.assert_running()
            print(f"\nruntime so far {time.monotonic() - self.started:.1f} s")


class ReplayInBrowser(unittest.TestCase):
    """`ubersim replay LOG --viewer` in the browser: a log that `ubersim run --referee builtin
    --record` wrote (Division B, 8 s), shown with the time slider. The page shows the replay bar
    and hides the world's controls; clicking on the slider seeks there, the button pauses, the
    speed select and the space key reach the replay."""

    REPLAY_JS = """
const v = window.ubersimViewer;
const s = v && v.state;
return {connected: !!(v && v.connected), replay: s && s.status ? s.status.replay || null : null, t: s ? s.t : null,
        robots: v && v.drawn ? v.drawn.robots.length : 0, slider: Number(document.getElementById('replay-slider').value),
        time: document.getElementById('replay-time').textContent, total: document.getElementById('replay-total').textContent,
        play: document.getElementById('replay-play').textContent, command: document.getElementById('sb-command').textContent};
"""

    @classmethod
    def setUpClass(cls):
        reason = browser_missing()
        if reason:
            raise unittest.SkipTest(reason)
        cls.workdir = tempfile.mkdtemp(prefix="ubersim_viewer_replay_")
        cls.addClassCleanup(shutil.rmtree, cls.workdir, ignore_errors=True)
        cls.log = os.path.join(cls.workdir, "match.log.gz")
        vision_port, referee_port, tracker_port = harness.free_udp_ports(3)
        run = subprocess.run([harness.BINARY, "run", "div-b", "--local-only", "--no-viewer", "--no-transport",
                              "ssl_simulation", "--no-transport", "grsim", "--fast", "--duration", "8", "-q",
                              "--referee", "builtin", "--vision-port", str(vision_port), "--referee-port",
                              str(referee_port), "--tracker-port", str(tracker_port), "--record", cls.log],
                             capture_output=True, text=True, timeout=120)
        assert run.returncode == 0, run.stdout + run.stderr
        cls.output_path = os.path.join(cls.workdir, "replay.txt")
        cls.output_file = open(cls.output_path, "wb")
        cls.addClassCleanup(cls.output_file.close)
        cls.process = subprocess.Popen([harness.BINARY, "replay", cls.log, "--viewer", "--viewer-port", "0",
                                        "--local-only"], stdout=cls.output_file, stderr=subprocess.STDOUT,
                                       stdin=subprocess.DEVNULL)
        cls.addClassCleanup(cls.stop_replay)
        match = harness.wait_for(lambda: re.search(r"viewer: (http://127\.0\.0\.1:\d+/)", cls.output()), 30.0,
                                 interval=0.05, what="the replay's viewer address")
        cls.driver_log = os.path.join(cls.workdir, "chromedriver.log")
        cls.driver = start_chromium(cls.workdir, cls.driver_log)
        cls.addClassCleanup(cls.driver.quit)
        cls.driver.get(match.group(1))
        harness.wait_for(lambda: (lambda r: r["connected"] and r["replay"] and r["robots"] >= 10)(cls.page()), 30.0,
                         interval=0.05, what="the replay on the page, drawing robots")

    @classmethod
    def output(cls):
        with open(cls.output_path, encoding="utf-8", errors="replace") as f:
            return f.read()

    @classmethod
    def stop_replay(cls):
        if cls.process.poll() is None:
            cls.process.send_signal(signal.SIGINT)
            try:
                cls.process.wait(timeout=15)
            except subprocess.TimeoutExpired:
                cls.process.kill()
                cls.process.wait(timeout=5)

    @classmethod
    def page(cls):
        return cls.driver.execute_script(cls.REPLAY_JS)

    def test_the_slider_seeks_and_the_controls_reach_the_replay(self):
        # Each answer is a round trip through the replaying simulator; on a loaded machine (the
        # sanitizer build, two suites' worth of work on two cores) 5 s was seen to run out.
        patience = 15.0
        try:
            displayed = lambda element_id: self.driver.find_element(By.ID, element_id).is_displayed()  # noqa: E731
            self.assertTrue(displayed("replay-bar"))
            for live_only in ("pause", "step", "reset", "chip", "kick-mode"):
                self.assertFalse(displayed(live_only), f"#{live_only} is shown in a replay")
            self.assertTrue(displayed("scoreboard"))
            p = self.page()
            duration = p["replay"]["duration"]
            self.assertAlmostEqual(duration, 8.0, delta=0.1)
            self.assertEqual(p["total"], "0:08.0")

            # The button pauses; the page says so. On a loaded machine the 8 s replay may have
            # played out before this test began: its button then starts it again first.
            if not p["replay"]["playing"]:
                self.driver.find_element(By.ID, "replay-play").click()
                harness.wait_for(lambda: self.page()["replay"]["playing"] or None, patience,
                                 what="the replay playing again")
            self.driver.find_element(By.ID, "replay-play").click()
            p = harness.wait_for(lambda: (lambda r: r if not r["replay"]["playing"] else None)(self.page()), patience,
                                 what="the replay paused")
            self.assertEqual(p["play"], "Play")

            # A click on the slider at three quarters of its width seeks there.
            slider = self.driver.find_element(By.ID, "replay-slider")
            rect = self.driver.execute_script("return arguments[0].getBoundingClientRect().toJSON();", slider)
            actions = ActionBuilder(self.driver)
            actions.pointer_action.move_to_location(int(rect["left"] + 0.75 * rect["width"]),
                                                    int(rect["top"] + rect["height"] / 2))
            actions.pointer_action.click()
            actions.perform()
            p = harness.wait_for(lambda: (lambda r: r if abs(r["replay"]["t"] - r["slider"]) < 1e-3
                                          and r["slider"] > 0.6 * duration else None)(self.page()),
                                 patience, what="the replay at the slider's time")
            self.assertLess(p["slider"], 0.9 * duration)
            self.assertFalse(p["replay"]["playing"], "a seek keeps it paused")
            self.assertAlmostEqual(p["t"], p["replay"]["t"], delta=1e-3)
            self.assertNotEqual(p["command"], "", "the scoreboard shows the log's match")

            # The speed select and the space key.
            self.driver.execute_script("""const s = document.getElementById('replay-speed');
                s.value = '4'; s.dispatchEvent(new Event('change'));""")
            harness.wait_for(lambda: self.page()["replay"]["speed"] == 4, patience, what="speed 4 on the replay")
            self.driver.find_element(By.TAG_NAME, "body").send_keys(" ")
            harness.wait_for(lambda: self.page()["replay"]["playing"], patience, what="playing after the space key")
            path = os.path.join(output_directory(), "viewer-replay.png")
            self.assertTrue(self.driver.save_screenshot(path))
            print(f"\nreplay page: {self.page()}; screenshot {path}")
            severe = [e for e in self.driver.get_log("browser") if e.get("level") == "SEVERE"]
            self.assertEqual(severe, [])
        except AssertionError as e:
            raise AssertionError(f"{e}\n--- ubersim replay ---\n{self.output()}") from e


if __name__ == "__main__":
    unittest.main()
