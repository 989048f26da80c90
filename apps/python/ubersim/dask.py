# SPDX-License-Identifier: Apache-2.0
"""Many seeded worlds, parameter sweeps and evaluation matches as Dask tasks (docs/python.md, Dask).

    from distributed import Client
    import ubersim.dask as ud

    with ud.local_cluster(2) as cluster, Client(cluster) as client:   # or Client("tcp://host:8786")
        results = ud.run_worlds(client, "div-b", seeds=range(8), duration=20.0)
    for r in results:
        print(r.seed, r.error or hex(r.state_hash), r.statistics["mean_robot_speed"])

- run_worlds: one task per seed, each a World stepped for `duration` simulated seconds (the bench's
  seeded random play, or idle robots): its state hash, statistics and, when asked, its trajectory.
- sweep: one task per (parameters, seed): World keyword overrides (physics keys, a robot model, a
  profile), each result carrying the settings it ran with.
- evaluate_matches: one ParallelEnv match per seed, teams driven by the scripted baseline, random
  play, idle robots or a picklable policy; goals counted against the field's geometry.

Results come back in the order of the inputs. A world that fails (a model error, a missing plugin,
a policy that raises) comes back with `error` set and the others finish. The same seeds give the
same state hashes on one worker or many: a world is deterministic per seed.

One world per thread at a time: ODE keeps one process-wide random generator (each world saves and
restores its own sequence around its step), so ubersim's C++ module serialises every ODE call of
a process behind one lock. Two threads of one worker then take turns instead of running side by
side: start workers with one thread each (`threads_per_worker=1`, `dask worker --nthreads 1`) and
as many worker processes as cores. The tasks here use no threads of their own.

This module imports `distributed` (Debian's python3-distributed) only when it talks to a cluster;
`import ubersim` does not import it.
"""
import dataclasses
import math
import os
import sys
import time
import warnings
from typing import Any, Callable, Dict, List, Optional, Union

import numpy as np

from .tasks import Task

__all__ = ["WorldResult", "MatchResult", "run_worlds", "sweep", "evaluate_matches", "local_cluster",
           "run_world", "play_match"]

PLAYS = ("random", "idle")
DRIVERS = ("scripted", "random", "idle")
# The keys a sweep's parameter dict may set: World's keyword arguments, and how the robots play.
SWEEP_KEYS = ("world", "profile", "physics", "robot", "plugin_paths", "play")
# Statistics are sampled this often (simulated s) when no trajectory is recorded.
STATISTICS_EVERY = 0.1


@dataclasses.dataclass
class WorldResult:
    """What one seeded world gave back (a run_worlds or sweep task).

    seed, params: the world's seed and every setting it ran with (world, profile, physics, robot,
    plugin_paths, play, duration, record_every). state_hash: World.state_hash at the end (None when
    it failed). sim_time (s), steps, wall_time (s, in the worker, loading included). statistics:
    mean_robot_speed, max_robot_speed (m/s, present robots), mean_ball_speed, max_ball_speed (m/s,
    on the carpet's plane), ball_distance (m the ball travelled, at the sampling interval),
    robot_off_field_fraction, ball_off_field_fraction (of the samples, outside the field lines),
    robots_off_field (present robots outside the field lines at the end), samples. trajectory (when
    record_every was given): time T, robot_ids N×2, robot_pose T×N×3, robot_velocity T×N×3,
    robot_present T×N, ball_position T×3, ball_velocity T×3. error: None, or "Type: message" (with
    its exit code, also in exit_code, when the exception has one). worker: the Dask worker's
    address. log: what the world logged (warnings)."""

    seed: int
    params: Dict[str, Any]
    state_hash: Optional[int] = None
    sim_time: float = 0.0
    wall_time: float = 0.0
    steps: int = 0
    statistics: Dict[str, float] = dataclasses.field(default_factory=dict)
    trajectory: Optional[Dict[str, np.ndarray]] = None
    error: Optional[str] = None
    exit_code: Optional[int] = None
    worker: Optional[str] = None
    log: str = ""

    @property
    def ok(self) -> bool:
        """True when the world ran to its end."""
        return self.error is None


@dataclasses.dataclass
class MatchResult:
    """What one evaluation match gave back (an evaluate_matches task).

    goals: {'blue': n, 'yellow': n} (blue attacks the goal at +x); outs: the times the ball left
    the field elsewhere. After a goal (and, with restart_on_out, an out) the world starts again
    from the world file's positions. state_hash: the world's at the end; sim_time (s) simulated;
    wall_time (s) in the worker; error, exit_code, worker and params as in WorldResult."""

    seed: int
    params: Dict[str, Any]
    goals: Dict[str, int] = dataclasses.field(default_factory=lambda: {"blue": 0, "yellow": 0})
    outs: int = 0
    state_hash: Optional[int] = None
    sim_time: float = 0.0
    wall_time: float = 0.0
    error: Optional[str] = None
    exit_code: Optional[int] = None
    worker: Optional[str] = None

    @property
    def ok(self) -> bool:
        """True when the match ran to its end."""
        return self.error is None


# --- The tasks: plain functions of picklable arguments, run in a worker (or anywhere). ---

def _describe(exc):
    """(text, exit code) of an exception: "Type: message", with its exit code when it has one."""
    code = getattr(exc, "exit_code", None)
    text = f"{type(exc).__name__}: {exc}"
    if code is not None:
        text += f" (exit code {code})"
    return text, code


def _worker_address():
    try:
        from distributed import get_worker
        return get_worker().address
    except (ImportError, ValueError):  # not inside a Dask worker
        return None


def _off_field(xy, field):
    """True where (…, 2) points lie outside the field lines."""
    return (np.abs(xy[..., 0]) > 0.5 * field["field_length"]) | (np.abs(xy[..., 1]) > 0.5 * field["field_width"])


class _Statistics:
    """A world's statistics, accumulated over its sampled states (World.state() dicts)."""

    def __init__(self, field):
        self.field = field
        self.samples = 0
        self.robot_samples = self.robot_speed_sum = self.robot_speed_max = self.robots_off = 0.0
        self.ball_speed_sum = self.ball_speed_max = self.ball_distance = self.ball_off = 0.0
        self.ball_last = None
        self.robots_off_now = 0

    def add(self, state):
        present = state["robot_present"]
        speed = np.hypot(state["robot_velocity"][present, 0], state["robot_velocity"][present, 1])
        off = _off_field(state["robot_pose"][present, :2], self.field)
        ball = state["ball_position"][:2]
        ball_speed = float(np.hypot(*state["ball_velocity"][:2]))
        self.samples += 1
        self.robot_samples += speed.size
        self.robot_speed_sum += float(speed.sum())
        self.robot_speed_max = max(self.robot_speed_max, float(speed.max()) if speed.size else 0.0)
        self.robots_off_now = int(off.sum())
        self.robots_off += self.robots_off_now
        self.ball_speed_sum += ball_speed
        self.ball_speed_max = max(self.ball_speed_max, ball_speed)
        self.ball_off += bool(_off_field(ball, self.field))
        if self.ball_last is not None:
            self.ball_distance += float(np.hypot(*(ball - self.ball_last)))
        self.ball_last = ball.copy()

    def result(self):
        robots, samples = max(1.0, self.robot_samples), max(1, self.samples)
        return {
            "mean_robot_speed": self.robot_speed_sum / robots,
            "max_robot_speed": self.robot_speed_max,
            "mean_ball_speed": self.ball_speed_sum / samples,
            "max_ball_speed": self.ball_speed_max,
            "ball_distance": self.ball_distance,
            "robot_off_field_fraction": self.robots_off / robots,
            "ball_off_field_fraction": self.ball_off / samples,
            "robots_off_field": self.robots_off_now,
            "samples": self.samples,
        }


def _trajectory(samples):
    return {
        "time": np.array([s["time"] for s in samples], np.float64),
        "robot_ids": np.array(samples[0]["robot_ids"]),
        "robot_pose": np.stack([s["robot_pose"] for s in samples]),
        "robot_velocity": np.stack([s["robot_velocity"] for s in samples]),
        "robot_present": np.stack([s["robot_present"] for s in samples]),
        "ball_position": np.stack([s["ball_position"] for s in samples]),
        "ball_velocity": np.stack([s["ball_velocity"] for s in samples]),
    }


def run_world(seed, params):
    """One seeded world, run in this process: the body of a run_worlds or sweep task.

    params: world, profile, physics, robot, plugin_paths, play ('random' or 'idle'), duration (s),
    record_every (s or None). Never raises on the world's account: a failure is the result's error."""
    import ubersim

    result = WorldResult(seed=int(seed), params=dict(params), worker=_worker_address())
    start = time.perf_counter()
    world = None
    try:
        world = ubersim.World(params["world"], plugin_paths=params.get("plugin_paths", ()), seed=int(seed),
                              profile=params.get("profile"), physics=params.get("physics"),
                              robot=params.get("robot"))
        if params.get("play", "random") == "random":
            world.random_play(int(seed))
        elif params.get("play") != "idle":
            raise ValueError(f"play must be 'random' or 'idle', not {params.get('play')!r}")
        total = int(round(float(params["duration"]) / world.step_seconds))
        record_every = params.get("record_every")
        every = record_every if record_every is not None else STATISTICS_EVERY
        chunk = max(1, int(round(float(every) / world.step_seconds)))
        statistics = _Statistics(world.field)
        samples = []  # the trajectory's states, when one is recorded
        state = world.state()
        done = 0
        while True:
            statistics.add(state)
            if record_every is not None:
                samples.append(state)
            if done == total:
                break
            n = min(chunk, total - done)
            world.step(n)
            done += n
            state = world.state()
        result.state_hash = int(world.state_hash)
        result.sim_time = float(world.time)
        result.steps = int(world.steps)
        result.statistics = statistics.result()
        if record_every is not None:
            result.trajectory = _trajectory(samples)
    except Exception as exc:  # a failing world is a result, so that the others finish
        result.error, result.exit_code = _describe(exc)
    finally:
        if world is not None:
            result.log = world.log
        result.wall_time = time.perf_counter() - start
    return result


class _Scoreboard(Task):
    """Counts the goals and outs of a match's world; a goal (an out too, with restart_on_out) ends
    the episode, and the env starts the world again from the world file's positions."""

    def __init__(self, restart_on_out):
        self.restart_on_out = restart_on_out
        self.goals = [0, 0]
        self.outs = 0

    def evaluate(self, obs, actions, env):
        blue, yellow, out = self._ball_events(obs, env.field)
        self.goals[0] += int(blue.sum())
        self.goals[1] += int(yellow.sum())
        self.outs += int(out.sum())
        ended = blue | yellow | (out if self.restart_on_out else np.zeros_like(out))
        return blue.astype(np.float64) - yellow, ended


def play_match(seed, params, blue="scripted", yellow="random"):
    """One evaluation match, run in this process: the body of an evaluate_matches task.

    blue, yellow: 'scripted', 'random', 'idle', or a policy: a callable obs → actions, obs the
    team's view of one world (robots × ubersim.env.FEATURES, its own robots first, the field turned
    so that it attacks +x), actions its robots × 6 (ubersim.env.ACTION). params: world, profile,
    physics, robot, plugin_paths, frame_skip, duration (s), restart_on_out."""
    import ubersim

    result = MatchResult(seed=int(seed), params=dict(params), worker=_worker_address())
    start = time.perf_counter()
    try:
        policies = {0: blue if callable(blue) else None, 1: yellow if callable(yellow) else None}
        for team in (blue, yellow):
            if not callable(team) and team not in DRIVERS:
                raise ValueError(f"a team is 'scripted', 'random', 'idle' or a policy, not {team!r}")
        scoreboard = _Scoreboard(bool(params.get("restart_on_out", True)))
        frame_skip = int(params.get("frame_skip", 5))
        env = ubersim.ParallelEnv(params["world"], 1, task=scoreboard,
                                  blue="agent" if callable(blue) else blue,
                                  yellow="agent" if callable(yellow) else yellow,
                                  frame_skip=frame_skip, seed=int(seed), profile=params.get("profile"),
                                  physics=params.get("physics"), robot=params.get("robot"),
                                  plugin_paths=params.get("plugin_paths", ()))
        observations, _ = env.reset(seed=int(seed))
        agents = env.possible_agents
        columns = {team: [j for j, a in enumerate(agents) if a.startswith(("blue_", "yellow_")[team])]
                   for team in (0, 1)}
        actions = np.zeros((1, len(agents), 6), np.float32)
        total = int(round(float(params["duration"]) / (env.worlds.step_seconds * frame_skip)))
        for _ in range(total):
            for team, policy in policies.items():
                if policy is not None and columns[team]:
                    view = observations[agents[columns[team][0]]][0]
                    out = np.asarray(policy(view), np.float32).reshape(len(columns[team]), 6)
                    actions[0, columns[team]] = out
            observations, _, _, _, _ = env.step_array(actions)
        result.goals = {"blue": scoreboard.goals[0], "yellow": scoreboard.goals[1]}
        result.outs = scoreboard.outs
        result.state_hash = int(env.worlds.state_hash(0))
        result.sim_time = total * frame_skip * env.worlds.step_seconds
        env.close()
    except Exception as exc:  # a failing match is a result, so that the others finish
        result.error, result.exit_code = _describe(exc)
    finally:
        result.wall_time = time.perf_counter() - start
    return result


# --- The client side. ---

def _distributed():
    try:
        import distributed
    except ImportError as exc:  # pragma: no cover - Debian's package is the documented route
        raise ImportError("ubersim.dask needs Dask's distributed scheduler: apt install python3-distributed "
                          "(for /usr/bin/python3)") from exc
    return distributed


def local_cluster(n_workers=2, **kwargs):
    """A LocalCluster for ubersim: n_workers processes of one thread each, on 127.0.0.1, no dashboard
    (its HTTP server on a free loopback port). Close it (or use it in a with block) when done."""
    distributed = _distributed()
    options = dict(n_workers=int(n_workers), threads_per_worker=1, processes=True, host="127.0.0.1",
                   scheduler_port=0, dashboard_address="127.0.0.1:0", scheduler_kwargs={"dashboard": False})
    options.update(kwargs)
    return distributed.LocalCluster(**options)


def _check_workers(client, stacklevel):
    """Warns when a worker runs several threads: ubersim's worlds then take turns within it."""
    try:
        workers = client.scheduler_info().get("workers", {})
    except Exception:  # an unusual client: nothing to check
        return
    crowded = sorted(w.get("nthreads", 1) for w in workers.values() if w.get("nthreads", 1) > 1)
    if crowded:
        warnings.warn(f"{len(crowded)} Dask worker(s) run {crowded[-1]} threads: ubersim steps one world per "
                      "process at a time (ODE's process-wide random generator), so the threads take turns. Start "
                      "workers with one thread each (threads_per_worker=1, dask worker --nthreads 1).",
                      RuntimeWarning, stacklevel=stacklevel + 1)


class _Bar:
    """A text progress bar on a stream (stderr): redrawn in place on a terminal, else a line at
    each tenth (so logs and pytest's captured output stay readable)."""

    WIDTH = 30

    def __init__(self, total, what, stream):
        self.total, self.what, self.stream = total, what, stream
        self.done = self.failed = 0
        self.start = time.monotonic()
        self.tty = bool(getattr(stream, "isatty", lambda: False)())
        self.last_tenth = -1
        self.draw()

    def update(self, ok):
        self.done += 1
        self.failed += 0 if ok else 1
        self.draw()

    def draw(self):
        fraction = self.done / self.total if self.total else 1.0
        text = f"{self.done}/{self.total} {self.what}"
        if self.failed:
            text += f", {self.failed} failed"
        text += f", {time.monotonic() - self.start:.1f} s"
        try:
            if self.tty:
                filled = int(round(fraction * self.WIDTH))
                self.stream.write(f"\r[{'#' * filled}{'.' * (self.WIDTH - filled)}] {text}\x1b[K")
                if self.done == self.total:
                    self.stream.write("\n")
            else:
                tenth = int(math.floor(fraction * 10))
                if tenth != self.last_tenth:
                    self.last_tenth = tenth
                    self.stream.write(f"ubersim.dask: {text}\n")
            self.stream.flush()
        except (OSError, ValueError):  # a closed stream never stops the work
            pass


def _stream(progress):
    if progress is True:
        return sys.stderr
    if progress is False or progress is None:
        return None
    if hasattr(progress, "write"):
        return progress
    raise ValueError("progress is True, False or a text stream")


def _collect(client, futures, failed, what, progress):
    """The futures' results in their order, driving a progress bar as they complete; a task that
    raised anyway (its worker died, the cluster went away) becomes failed(index, exception)."""
    distributed = _distributed()
    stream = _stream(progress)
    if not futures:
        return []
    bar = _Bar(len(futures), what, stream) if stream is not None else None
    index = {f.key: i for i, f in enumerate(futures)}
    results = [None] * len(futures)
    try:
        for future in distributed.as_completed(futures):
            i = index[future.key]
            try:
                results[i] = future.result()
            except Exception as exc:
                results[i] = failed(i, exc)
            if bar is not None:
                bar.update(results[i].ok)
    except BaseException:
        client.cancel(futures)
        raise
    return results


def _client(client):
    return client if client is not None else _distributed().default_client()


def _path(value):
    """A file given by a relative path, made absolute (a worker's directory may differ); names stay."""
    if value is None:
        return None
    text = os.fspath(value)
    return os.path.abspath(text) if os.path.exists(text) else text


def _settings(world, profile, physics, robot, plugin_paths, play):
    if play not in PLAYS:
        raise ValueError(f"play must be 'random' or 'idle', not {play!r}")
    return {"world": _path(world), "profile": profile, "physics": None if physics is None else dict(physics),
            "robot": _path(robot), "plugin_paths": [_path(p) for p in plugin_paths], "play": play}


def _check_run(duration, record_every):
    if not duration >= 0:
        raise ValueError(f"duration must be >= 0 s, not {duration!r}")
    if record_every is not None and not record_every > 0:
        raise ValueError(f"record_every must be > 0 s or None, not {record_every!r}")


def _submit_worlds(client, jobs, progress):
    """jobs: (seed, params) pairs → their WorldResults, in order."""
    client = _client(client)
    _check_workers(client, 3)
    futures = [client.submit(run_world, seed, params, pure=False, key=f"ubersim-world-{i}-{os.urandom(6).hex()}")
               for i, (seed, params) in enumerate(jobs)]

    def failed(i, exc):
        seed, params = jobs[i]
        text, code = _describe(exc)
        return WorldResult(seed=seed, params=params, error=text, exit_code=code)

    return _collect(client, futures, failed, "worlds", progress)


def run_worlds(client, world, seeds, duration, *, play="random", profile="fast", physics=None, robot=None,
               record_every=None, progress=True, plugin_paths=()) -> List[WorldResult]:
    """One Dask task per seed: World(world, seed=seed, profile, physics, robot) stepped for
    `duration` simulated seconds, its robots under the bench's random play seeded with the same
    seed (play='random') or idle (play='idle'). record_every (s): record the state that often into
    the result's trajectory. progress: a bar on stderr (True), none (False) or on a given stream.
    client: a distributed.Client (None: the default client). Returns a WorldResult per seed, in
    the seeds' order; a world that fails has its error set, and the others finish."""
    _check_run(duration, record_every)
    base = _settings(world, profile, physics, robot, plugin_paths, play)
    base.update(duration=float(duration), record_every=record_every)
    return _submit_worlds(client, [(int(s), dict(base)) for s in seeds], progress)


def sweep(client, world, parameters, seeds=(0,), duration=10.0, *, play="random", profile="fast", physics=None,
          robot=None, record_every=None, progress=True, plugin_paths=()) -> List[WorldResult]:
    """One Dask task per (parameters, seed): run_worlds with each dict of `parameters` over the
    settings given here, e.g. {"physics": {"step": 0.002}}, {"robot": "my-robot.yaml"},
    {"profile": "precise"} (keys: world, profile, physics, robot, plugin_paths, play; physics keys
    are merged into `physics`). Returns len(parameters) × len(seeds) results, parameters first then
    seeds, each with its full settings in params."""
    _check_run(duration, record_every)
    seeds = [int(s) for s in seeds]
    jobs = []
    for overrides in parameters:
        unknown = set(overrides) - set(SWEEP_KEYS)
        if unknown:
            raise ValueError(f"a sweep's parameters set {', '.join(SWEEP_KEYS)}, not {', '.join(sorted(unknown))}")
        merged_physics = dict(physics or {})
        merged_physics.update(overrides.get("physics") or {})
        merged = {"world": world, "profile": profile, "physics": merged_physics or None, "robot": robot,
                  "plugin_paths": plugin_paths, "play": play}
        merged.update({k: v for k, v in overrides.items() if k != "physics"})
        params = _settings(**merged)
        params.update(duration=float(duration), record_every=record_every)
        jobs.extend((s, dict(params)) for s in seeds)
    return _submit_worlds(client, jobs, progress)


def _team_name(team):
    """A team's driver, or "policy <name>" for a callable."""
    return team if isinstance(team, str) else f"policy {getattr(team, '__qualname__', repr(team))}"


def evaluate_matches(client, world, seeds, duration, *, blue: Union[str, Callable] = "scripted",
                     yellow: Union[str, Callable] = "random", frame_skip=5, profile="fast", physics=None, robot=None,
                     restart_on_out=True, progress=True, plugin_paths=()) -> List[MatchResult]:
    """One Dask task per seed: a match of `duration` simulated seconds in ParallelEnv(world, 1,
    blue=…, yellow=…, seed=seed). A team is 'scripted' (the baseline), 'random' (the bench's random
    play), 'idle', or a picklable policy: obs → actions (see play_match). Goals are counted when
    the ball crosses a goal line between the posts and under the bar; the world then starts again
    from its start positions (after the ball leaves the field elsewhere too, with restart_on_out).
    Returns a MatchResult per seed, in the seeds' order."""
    _check_run(duration, None)
    for team in (blue, yellow):
        if not callable(team) and team not in DRIVERS:
            raise ValueError(f"a team is 'scripted', 'random', 'idle' or a policy, not {team!r}")
    client = _client(client)
    _check_workers(client, 2)
    params = {"world": _path(world), "profile": profile, "physics": None if physics is None else dict(physics),
              "robot": _path(robot), "plugin_paths": [_path(p) for p in plugin_paths], "frame_skip": int(frame_skip),
              "duration": float(duration), "restart_on_out": bool(restart_on_out),
              "blue": _team_name(blue), "yellow": _team_name(yellow)}
    seeds = [int(s) for s in seeds]
    futures = [client.submit(play_match, s, params, blue, yellow, pure=False,
                             key=f"ubersim-match-{i}-{os.urandom(6).hex()}") for i, s in enumerate(seeds)]

    def failed(i, exc):
        text, code = _describe(exc)
        return MatchResult(seed=seeds[i], params=dict(params), error=text, exit_code=code)

    return _collect(client, futures, failed, "matches", progress)
