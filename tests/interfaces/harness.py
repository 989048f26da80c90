# SPDX-License-Identifier: Apache-2.0
"""Harness for the protocol tests: `ubersim run` in its own process, real sockets around it.

A test copies a shipped world into a temporary file with its own transports on free ports
(`World`), starts the simulator on it (`Simulator`, a context manager that stops it with SIGINT
and a timeout), and talks to it with `UdpClient` and `MulticastReceiver`. Every wait is bounded;
`wait_for` polls a condition until a deadline instead of sleeping a fixed time.

Environment (set by tests/interfaces/CMakeLists.txt): UBERSIM_BINARY, UBERSIM_SOURCE_DIR, and
PYTHONPATH with the generated *_pb2 modules.
"""
import copy
import os
import signal
import socket
import struct
import subprocess
import tempfile
import time

import yaml

BINARY = os.environ.get("UBERSIM_BINARY", "ubersim")
SOURCE_DIR = os.environ.get("UBERSIM_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
MODELS_DIR = os.path.join(SOURCE_DIR, "models")
LOOPBACK = "127.0.0.1"
VISION_GROUP = "224.5.23.2"


def free_udp_ports(count, host=LOOPBACK):
    """`count` distinct UDP ports that are free on `host` right now (bound to port 0, then closed)."""
    sockets = []
    try:
        for _ in range(count):
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            s.bind((host, 0))
            sockets.append(s)
        return [s.getsockname()[1] for s in sockets]
    finally:
        for s in sockets:
            s.close()


def wait_for(condition, timeout, interval=0.01, what="condition"):
    """Calls `condition()` until it returns something truthy (returned) or `timeout` s pass
    (raises AssertionError naming `what`)."""
    deadline = time.monotonic() + timeout
    while True:
        value = condition()
        if value:
            return value
        if time.monotonic() >= deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        time.sleep(interval)


class World:
    """A shipped world (models/worlds/NAME.yaml) as a dict, its relative paths made absolute, to
    change and write to a temporary file."""

    def __init__(self, name="div-b"):
        path = os.path.join(MODELS_DIR, "worlds", name + ".yaml")
        with open(path, encoding="utf-8") as f:
            self.data = yaml.safe_load(f)
        base = os.path.dirname(path)

        def absolute(p):
            return p if os.path.isabs(p) else os.path.normpath(os.path.join(base, p))

        for key in ("field", "ball"):
            self.data[key] = absolute(self.data[key])
        for robot in self.data.get("robots", []):
            robot["model"] = absolute(robot["model"])
        self.data["fields"] = [absolute(p) for p in self.data.get("fields", [])]
        for team in self.data.get("teams", {}).values():
            team["model"] = absolute(team["model"])
        self.data["plugin_paths"] = [absolute(p) for p in self.data.get("plugin_paths", [])]
        self.data["transports"] = []

    def add_transport(self, plugin, **params):
        """Adds a transport block: {plugin: PLUGIN, **params}."""
        self.data["transports"].append(dict(plugin=plugin, **params))
        return self

    def set_perception(self, **values):
        """Overrides keys of the perception block (e.g. preset="ideal", latency=0.02)."""
        self.data.setdefault("perception", {}).update(values)
        return self

    def set_radio(self, **values):
        """Overrides keys of the radio block (e.g. preset="ideal")."""
        self.data.setdefault("radio", {}).update(values)
        return self

    def keep_robots(self, per_team):
        """Keeps the first `per_team` robots of each team (a lighter world keeps real time on a
        busy machine)."""
        kept = self.robots("blue")[:per_team] + self.robots("yellow")[:per_team]
        self.data["robots"] = kept
        return self

    def robots(self, team=None):
        """The robot placements, optionally of one team ("blue", "yellow")."""
        return [r for r in self.data.get("robots", []) if team is None or r["team"] == team]

    def write(self, directory):
        """Writes the world to DIRECTORY/world.yaml and returns the path."""
        path = os.path.join(directory, "world.yaml")
        with open(path, "w", encoding="utf-8") as f:
            yaml.safe_dump(copy.deepcopy(self.data), f, sort_keys=False)
        return path


class Simulator:
    """`ubersim run WORLD` as a subprocess; stderr and stdout go to a log file (read with
    output()). Use as a context manager; the process is stopped with SIGINT, then killed after
    `stop_timeout` s. `local_only` (the default) passes --local-only: only a test inside a network
    namespace of its own (netns.py) may leave it off."""

    def __init__(self, world, fast=False, speed=None, duration=None, paused=False, extra_args=(),
                 stop_timeout=15.0, local_only=True):
        self.world = world
        self.stop_timeout = stop_timeout
        self._dir = tempfile.TemporaryDirectory(prefix="ubersim_interfaces_")
        # A World is written to a temporary file; a path (a shipped world, as a user runs it) is used as it is.
        self.world_file = world if isinstance(world, str) else world.write(self._dir.name)
        self.log_path = os.path.join(self._dir.name, "ubersim.log")
        self.args = [BINARY, "run", self.world_file, "--quiet"]
        # Outside a network namespace of its own a test never sends on the machine's interfaces.
        if local_only:
            self.args.append("--local-only")
        if fast:
            self.args.append("--fast")
        if speed is not None:
            self.args += ["--speed", str(speed)]
        if duration is not None:
            self.args += ["--duration", str(duration)]
        if paused:
            self.args.append("--paused")
        self.args += list(extra_args)
        self.process = None
        self.returncode = None

    def start(self):
        """Starts the process (does not wait for it to be ready: wait for its packets)."""
        self._log = open(self.log_path, "wb")
        self.process = subprocess.Popen(self.args, stdout=self._log, stderr=subprocess.STDOUT,
                                        stdin=subprocess.DEVNULL)
        return self

    def running(self):
        """True while the process lives."""
        return self.process is not None and self.process.poll() is None

    def assert_running(self):
        """Raises AssertionError with the log when the process has ended."""
        if not self.running():
            raise AssertionError(f"ubersim exited with {self.process.poll()}:\n{self.output()}")

    def wait(self, timeout):
        """Waits for the process to end by itself; returns its exit code (raises on timeout)."""
        try:
            self.returncode = self.process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.stop()
            raise AssertionError(f"ubersim did not end within {timeout} s:\n{self.output()}")
        return self.returncode

    def stop(self):
        """SIGINT, then SIGKILL after stop_timeout s; returns the exit code."""
        if self.process is None:
            return None
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(timeout=self.stop_timeout)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(timeout=5)
        self.returncode = self.process.returncode
        return self.returncode

    def output(self):
        """Everything the process wrote so far."""
        if hasattr(self, "_log"):
            self._log.flush()
        try:
            with open(self.log_path, encoding="utf-8", errors="replace") as f:
                return f.read()
        except FileNotFoundError:
            return ""

    def close(self):
        """Stops the process and removes the temporary files."""
        self.stop()
        if hasattr(self, "_log"):
            self._log.close()
        self._dir.cleanup()

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.close()
        return False


class UdpClient:
    """A UDP socket on the loopback (bound to `port`, 0 = any free one) that sends to the
    simulator and receives its replies."""

    def __init__(self, port=0, host=LOOPBACK):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind((host, port))
        self.address = self.sock.getsockname()

    def send(self, data, port, host=LOOPBACK):
        """Sends bytes (or a protobuf message) to host:port."""
        if hasattr(data, "SerializeToString"):
            data = data.SerializeToString()
        self.sock.sendto(data, (host, port))

    def recv(self, timeout):
        """(bytes, sender) of the next datagram, or None after `timeout` s."""
        self.sock.settimeout(max(timeout, 1e-4))  # 0 would make the socket non-blocking
        try:
            return self.sock.recvfrom(65536)
        except (socket.timeout, BlockingIOError):
            return None

    def close(self):
        self.sock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


class MulticastReceiver:
    """Receives a multicast group on one port, joined on the interface `interface` (loopback by
    default: works with no network; "0.0.0.0" lets the system pick, as most team software does).
    `bind_any` binds ("", port), as team software and grSim's clients do, instead of the group."""

    def __init__(self, port, group=VISION_GROUP, interface=LOOPBACK, bind_any=False):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.sock.bind(("" if bind_any else group, port))
        membership = struct.pack("4s4s", socket.inet_aton(group), socket.inet_aton(interface))
        self.sock.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, membership)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)

    def recv(self, timeout):
        """Bytes of the next datagram, or None after `timeout` s."""
        received = self.recv_from(timeout)
        return received[0] if received else None

    def recv_from(self, timeout):
        """(bytes, (source address, port)) of the next datagram, or None after `timeout` s."""
        self.sock.settimeout(max(timeout, 1e-4))  # 0 would make the socket non-blocking
        try:
            return self.sock.recvfrom(65536)
        except (socket.timeout, BlockingIOError):
            return None

    def recv_until(self, predicate, timeout, parse=None):
        """Receives until `predicate(item)` is true for an item (returned) or `timeout` s pass
        (AssertionError). Items are `parse(bytes)` when `parse` is given, else the bytes."""
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise AssertionError(f"no matching datagram within {timeout} s")
            data = self.recv(left)
            if data is None:
                continue
            item = parse(data) if parse else data
            if predicate(item):
                return item

    def collect_until(self, done, timeout, parse=None):
        """Every datagram as (monotonic arrival time, item) until `done(items)` is true, checked
        after each datagram (returned), or `timeout` s pass (AssertionError). For windows measured
        in simulated time: a starved machine makes the simulator fall behind the wall clock."""
        out = []
        deadline = time.monotonic() + timeout
        while not done(out):
            left = deadline - time.monotonic()
            if left <= 0:
                raise AssertionError(f"collected {len(out)} datagrams in {timeout} s, not enough")
            data = self.recv(left)
            if data is not None:
                out.append((time.monotonic(), parse(data) if parse else data))
        return out

    def collect(self, duration, parse=None):
        """Every datagram received during `duration` s, as (monotonic arrival time, item)."""
        out = []
        deadline = time.monotonic() + duration
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                return out
            data = self.recv(left)
            if data is not None:
                out.append((time.monotonic(), parse(data) if parse else data))

    def drain(self):
        """Drops whatever is queued."""
        self.sock.setblocking(False)
        try:
            while True:
                self.sock.recv(65536)
        except BlockingIOError:
            pass
        finally:
            self.sock.setblocking(True)

    def close(self):
        self.sock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
