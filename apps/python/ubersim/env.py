# SPDX-License-Identifier: Apache-2.0
"""Gymnasium-shaped environments over K worlds stepped by one call into C++ (docs/python.md).

- VectorEnv: K worlds, one controlled team (or both), gymnasium's VectorEnv API, auto-reset.
- Env: one world, gymnasium's Env API.
- ParallelEnv: K worlds, every robot of both teams an agent, PettingZoo's parallel API.

Observations are one float32 array, K × robots × features (FEATURES names them), written in
place by C++; actions one float32 array, K × controlled robots × 6 (ACTION names them), read in
place. Everything is in SI units and the field frame (x towards the goal blue attacks), except
ParallelEnv's yellow view, which is turned so that each team attacks +x.
"""
import numpy as np

from . import _ubersim
from ._paths import plugin_paths as _plugin_paths
from .render import render_field
from .spaces import Box, EnvBase, VectorEnvBase

# The features of one robot row, in order (FEATURES_BASE of them, or all with camera_features).
FEATURES = (
    "present",        # 1 on the field, 0 off it (then every robot feature is 0)
    "x", "y",         # m, field frame
    "cos_yaw", "sin_yaw",  # heading
    "vx", "vy",       # m/s, field frame
    "omega",          # rad/s
    "kicker_ready",   # 1 when the kicker is charged
    "ball_contact",   # 1 when the dribbler touches the ball
    "ball_x", "ball_y", "ball_z",     # m (the same ball in every row)
    "ball_vx", "ball_vy", "ball_vz",  # m/s
    # camera_features=True: what the cameras reported, after noise, latency and drop-outs
    "seen",           # 1 when a camera frame that arrived during the last env step reported the robot
    "seen_x", "seen_y", "seen_cos_yaw", "seen_sin_yaw",  # its last report
    "ball_seen",      # 1 when a frame of the last env step reported a ball
    "ball_seen_x", "ball_seen_y",  # the last reported ball (on the carpet)
)
# The components of one robot's action, in order.
ACTION = (
    "forward", "left",  # m/s, the robot's frame
    "angular",          # rad/s
    "kick_speed",       # m/s; > 0 kicks when the ball is at the kicker and it is charged
    "chip_angle",       # rad: 0 flat, > 0 a chip at that elevation
    "dribbler",         # rad/s of the roller; 0 off
)
# Features that change sign when the field is turned by π about its centre (ParallelEnv's yellow view).
_TURNED = ("x", "y", "cos_yaw", "sin_yaw", "vx", "vy", "ball_x", "ball_y", "ball_vx", "ball_vy", "seen_x",
           "seen_y", "seen_cos_yaw", "seen_sin_yaw", "ball_seen_x", "ball_seen_y")
_MASK64 = (1 << 64) - 1


def _episode_seeds(world_seeds, episodes):
    """A seed per world and episode (splitmix64 of the two, vectorised): episodes differ, runs repeat."""
    z = np.asarray(world_seeds, np.uint64) * np.uint64(0x9E3779B97F4A7C15)  # wraps modulo 2^64, as meant
    z = z + np.asarray(episodes, np.uint64) + np.uint64(0x632BE59BD9B4E019)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


def _episode_seed(world_seed, episode):
    """The seed of one world's episode (_episode_seeds of one)."""
    return int(_episode_seeds([world_seed], [episode])[0])


def _drivers(controlled, opponent):
    """(blue, yellow) drivers of the C++ core from the controlled team(s) and the opponent."""
    if opponent not in ("idle", "scripted", "random"):
        raise ValueError(f"opponent must be 'idle', 'scripted' or 'random', not {opponent!r}")
    if controlled == "both":
        return "agent", "agent"
    if controlled == "blue":
        return "agent", opponent
    if controlled == "yellow":
        return opponent, "agent"
    if controlled == "none":
        return opponent, opponent
    raise ValueError(f"controlled must be 'blue', 'yellow', 'both' or 'none', not {controlled!r}")


class _Worlds:
    """K worlds with their buffers, seeds, episode counters and task: what every env here shares."""

    def __init__(self, world, num_envs, *, blue, yellow, task, frame_skip, max_episode_steps, camera_features,
                 seed, profile, physics, robot, plugin_paths):
        self.core = _ubersim.VectorWorlds(
            str(world), int(num_envs), frame_skip=int(frame_skip), blue=blue, yellow=yellow,
            camera_features=bool(camera_features), plugin_paths=_plugin_paths(plugin_paths), seed=seed,
            profile=profile, physics=physics, robot=None if robot is None else str(robot))
        self.num_envs = self.core.count
        self.robots = self.core.robots
        self.features = FEATURES[:self.core.features]
        self.slots = self.core.slots                      # robots × 2: team (0 blue, 1 yellow), id
        self.controlled = self.core.controlled            # rows the actions move
        self.field = self.core.field
        self.frame_skip = int(frame_skip)
        self.dt = self.core.step_seconds * self.frame_skip  # simulated seconds per env step
        self.task = task
        self.max_episode_steps = max_episode_steps if max_episode_steps is not None else getattr(
            task, "max_episode_steps", None)
        self.obs = np.zeros((self.num_envs, self.robots, self.core.features), np.float32)
        self.actions = np.zeros((self.num_envs, self.core.controlled_count, len(ACTION)), np.float32)
        bounds = self.core.action_bounds[:, self.controlled, :]
        self.action_low, self.action_high = bounds[0], bounds[1]
        self.episode_steps = np.zeros(self.num_envs, np.int64)
        self.episodes = np.zeros(self.num_envs, np.int64)
        self.world_seeds = np.zeros(self.num_envs, np.uint64)
        self.rng = np.random.default_rng(0)
        self.zero_reward = np.zeros((self.num_envs, 2), np.float64)
        self.never = np.zeros(self.num_envs, bool)

    def observation_bounds(self):
        """Low and high of one world's observation (robots × features)."""
        half_x = 0.5 * self.field["field_length"] + self.field["boundary_width"]
        half_y = 0.5 * self.field["field_width"] + self.field["boundary_width"]
        limits = {"present": (0, 1), "x": (-half_x, half_x), "y": (-half_y, half_y), "cos_yaw": (-1, 1),
                  "sin_yaw": (-1, 1), "kicker_ready": (0, 1), "ball_contact": (0, 1), "ball_x": (-half_x, half_x),
                  "ball_y": (-half_y, half_y), "ball_z": (0, np.inf), "seen": (0, 1), "seen_x": (-half_x, half_x),
                  "seen_y": (-half_y, half_y), "seen_cos_yaw": (-1, 1), "seen_sin_yaw": (-1, 1),
                  "ball_seen": (0, 1), "ball_seen_x": (-half_x, half_x), "ball_seen_y": (-half_y, half_y)}
        low = np.array([limits.get(f, (-np.inf, np.inf))[0] for f in self.features], np.float32)
        high = np.array([limits.get(f, (-np.inf, np.inf))[1] for f in self.features], np.float32)
        return np.broadcast_to(low, (self.robots, len(low))), np.broadcast_to(high, (self.robots, len(high)))

    def seed(self, seed):
        """World k's seed is seed + k; the task's generator is seeded with seed."""
        if seed is None:
            seed = int(np.random.SeedSequence().entropy & 0xFFFFFFFF)
        if isinstance(seed, (list, tuple, np.ndarray)):
            seeds = [int(s) for s in seed]
            if len(seeds) != self.num_envs:
                raise ValueError(f"{len(seeds)} seeds for {self.num_envs} worlds")
        else:
            seeds = [int(seed) + k for k in range(self.num_envs)]
        self.world_seeds = np.array([s & _MASK64 for s in seeds], np.uint64)
        self.rng = np.random.default_rng(seeds)
        self.episodes[:] = 0

    def reset(self, indices):
        """Starts the next episode of the worlds `indices` (the task's start, or the world file's)."""
        indices = np.asarray(indices, np.int64)
        seeds = _episode_seeds(self.world_seeds[indices], self.episodes[indices]).tolist()
        start = self.task.start(self.rng, indices, self) if hasattr(self.task, "start") else None
        if start is None:
            self.core.reset(indices.tolist(), seeds, self.obs)
        else:
            ball = start.get("ball")
            self.core.reset(indices.tolist(), seeds, self.obs,
                            robot_pose=start.get("robot_pose"), robot_present=start.get("robot_present"),
                            ball=None if ball is None else np.asarray(ball, np.float64))
        self.episodes[indices] += 1
        self.episode_steps[indices] = 0
        if hasattr(self.task, "begin"):
            self.task.begin(self.obs, indices, self)

    def evaluate(self, actions):
        """The task's rewards per team (K × 2: blue, yellow) and its terminations (K)."""
        if self.task is None:
            return self.zero_reward, self.never
        evaluate = self.task.evaluate if hasattr(self.task, "evaluate") else self.task
        reward, terminated = evaluate(self.obs, actions, self)
        reward = np.asarray(reward, np.float64)
        if reward.ndim == 1:  # one reward per world: the blue team's, the yellow's its opposite
            reward = np.stack([reward, -reward], axis=1)
        return reward, np.asarray(terminated, bool).reshape(self.num_envs)

    def step(self, actions, autoreset):
        """One env step of every world; returns (team rewards, terminated, truncated, final obs or None)."""
        np.clip(np.asarray(actions, np.float32).reshape(self.actions.shape), self.action_low, self.action_high,
                out=self.actions)
        self.core.step(self.actions, self.obs)
        self.episode_steps += 1
        reward, terminated = self.evaluate(self.actions)
        if self.max_episode_steps is not None:
            truncated = (self.episode_steps >= self.max_episode_steps) & ~terminated
        else:
            truncated = self.never.copy()
        final = None
        done = terminated | truncated
        if autoreset and done.any():
            final = self.obs.copy()
            self.reset(np.flatnonzero(done))
        return reward, terminated, truncated, final, done

    def render(self, k, width=640):
        """World k's field as an RGB array (H × W × 3 uint8)."""
        rows = self.obs[k]
        f = {name: i for i, name in enumerate(self.features)}
        pose = np.stack([rows[:, f["x"]], rows[:, f["y"]], np.arctan2(rows[:, f["sin_yaw"]], rows[:, f["cos_yaw"]])],
                        axis=1).astype(np.float64)
        ball = rows[0, [f["ball_x"], f["ball_y"], f["ball_z"]]].astype(np.float64)
        return render_field(self.field, self.slots, pose, rows[:, f["present"]] > 0.5, ball, width=width)


class _WorldsView:
    """What every env here tells of its worlds (self._w, a _Worlds)."""

    @property
    def worlds(self):
        """The C++ core: state_hash(k), save(k), restore(k, bytes), time(k), profile, physics_steps."""
        return self._w.core

    @property
    def features(self):
        """The names of the observation's features, in order."""
        return self._w.features

    @property
    def slots(self):
        """Each robot row's (team, id): team 0 blue, 1 yellow."""
        return self._w.slots

    @property
    def controlled_rows(self):
        """The robot rows the actions move, in the actions' order."""
        return self._w.controlled

    @property
    def field(self):
        """The field's geometry (m): sizes and markings."""
        return self._w.field

    @property
    def dt(self):
        """Simulated seconds per env step (frame_skip physics steps)."""
        return self._w.dt


class VectorEnv(_WorldsView, VectorEnvBase):
    """K worlds of one world file, stepped by one call into C++ (gymnasium's VectorEnv API).

    controlled: 'blue', 'yellow' or 'both' (the actions move that team's robots, or both's);
    opponent: 'idle', 'scripted' (a baseline team) or 'random' (the bench's random play) for the
    team not controlled. task: a Task (ubersim.tasks) or a callable (obs, actions, env) →
    (reward K or K × 2, terminated K). Worlds reset on their own when done (same step: the
    final observation is in info['final_obs']). copy=False returns the env's own observation
    buffer, overwritten by the next step, instead of a copy (as gymnasium's vector envs' copy)."""

    metadata = {"render_modes": ["rgb_array"], "autoreset_mode": "SameStep"}

    def __init__(self, world="div-b", num_envs=1, *, task=None, controlled="blue", opponent="idle", frame_skip=5,
                 max_episode_steps=None, camera_features=False, render_mode=None, seed=None, profile="fast",
                 physics=None, robot=None, plugin_paths=(), copy=True):
        blue, yellow = _drivers(controlled, opponent)
        self._copy = bool(copy)
        self._w = _Worlds(world, num_envs, blue=blue, yellow=yellow, task=task, frame_skip=frame_skip,
                          max_episode_steps=max_episode_steps, camera_features=camera_features, seed=seed,
                          profile=profile, physics=physics, robot=robot, plugin_paths=plugin_paths)
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', not {render_mode!r}")
        self.render_mode = render_mode
        self.num_envs = self._w.num_envs
        self.controlled = controlled
        self._team = 1 if controlled == "yellow" else 0
        low, high = self._w.observation_bounds()
        self.single_observation_space = Box(low, high, dtype=np.float32)
        self.single_action_space = Box(self._w.action_low, self._w.action_high, dtype=np.float32)
        k = self.num_envs
        self.observation_space = Box(np.broadcast_to(low, (k,) + low.shape), np.broadcast_to(high, (k,) + high.shape),
                                     dtype=np.float32)
        self.action_space = Box(np.broadcast_to(self._w.action_low, (k,) + self._w.action_low.shape),
                                np.broadcast_to(self._w.action_high, (k,) + self._w.action_high.shape),
                                dtype=np.float32)
        self._w.seed(seed)
        self._closed = False

    def reset(self, *, seed=None, options=None):
        """Starts a new episode in every world; seed: an int (world k gets seed + k) or one per world."""
        if seed is not None or not self._w.episodes.any():
            self._w.seed(seed)
            self.action_space.seed(seed)
            self.single_action_space.seed(seed)
        self._w.reset(np.arange(self.num_envs))
        return self._observation(), self._info()

    def step(self, actions):
        """One env step: (obs, reward, terminated, truncated, info), arrays over the K worlds."""
        reward, terminated, truncated, final, done = self._w.step(actions, autoreset=True)
        info = self._info()
        info["team_reward"] = reward
        if final is not None:
            info["final_obs"] = final
            info["_final_obs"] = done
        return self._observation(), reward[:, self._team].copy(), terminated, truncated, info

    def _observation(self):
        return self._w.obs.copy() if self._copy else self._w.obs

    def _info(self):
        return {"episode_step": self._w.episode_steps.copy(), "episode": self._w.episodes.copy()}

    def render(self):
        """Every world's field as an RGB array (a tuple of K), or None without render_mode."""
        if self.render_mode != "rgb_array":
            return None
        return tuple(self._w.render(k) for k in range(self.num_envs))

    def close(self):
        """Frees the worlds."""
        self._closed = True
        self._w = None

    @property
    def unwrapped(self):
        return self


class Env(_WorldsView, EnvBase):
    """One world in gymnasium's Env API: the same options as VectorEnv, no auto-reset."""

    metadata = {"render_modes": ["rgb_array"]}

    def __init__(self, world="div-b", *, task=None, controlled="blue", opponent="idle", frame_skip=5,
                 max_episode_steps=None, camera_features=False, render_mode=None, seed=None, profile="fast",
                 physics=None, robot=None, plugin_paths=()):
        blue, yellow = _drivers(controlled, opponent)
        self._w = _Worlds(world, 1, blue=blue, yellow=yellow, task=task, frame_skip=frame_skip,
                          max_episode_steps=max_episode_steps, camera_features=camera_features, seed=seed,
                          profile=profile, physics=physics, robot=robot, plugin_paths=plugin_paths)
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', not {render_mode!r}")
        self.render_mode = render_mode
        self._team = 1 if controlled == "yellow" else 0
        low, high = self._w.observation_bounds()
        self.observation_space = Box(low, high, dtype=np.float32)
        self.action_space = Box(self._w.action_low, self._w.action_high, dtype=np.float32)
        self._w.seed(seed)

    @property
    def world(self):
        """The C++ core of the one world (state_hash(0), save(0), restore(0, bytes))."""
        return self._w.core

    def reset(self, *, seed=None, options=None):
        """Starts a new episode: (obs, info)."""
        if seed is not None or not self._w.episodes.any():
            self._w.seed(seed)
            self.action_space.seed(seed)
        self._w.reset(np.array([0]))
        return self._w.obs[0].copy(), {"episode": int(self._w.episodes[0])}

    def step(self, action):
        """One env step: (obs, reward, terminated, truncated, info)."""
        reward, terminated, truncated, _, _ = self._w.step(np.asarray(action, np.float32)[None], autoreset=False)
        return (self._w.obs[0].copy(), float(reward[0, self._team]), bool(terminated[0]), bool(truncated[0]),
                {"episode_step": int(self._w.episode_steps[0]), "team_reward": reward[0].copy()})

    def render(self):
        """The field as an RGB array, or None without render_mode."""
        return self._w.render(0) if self.render_mode == "rgb_array" else None

    def close(self):
        """Frees the world."""
        self._w = None

    @property
    def unwrapped(self):
        return self


class ParallelEnv(_WorldsView):
    """Every robot of both teams an agent, over K worlds (PettingZoo's parallel API, batched).

    Agents are named 'blue_0' … 'yellow_10'. Each value of the observation, reward, termination
    and truncation dicts has the K worlds as its first axis. An agent observes its team's view:
    its own team's rows first, then the other team's, in a frame where its team attacks +x (the
    field turned by π for yellow), so one policy plays both sides; env.agent_row[agent] is its
    own row in that view. A team may be left to 'scripted', 'random' or 'idle' instead."""

    metadata = {"render_modes": ["rgb_array"], "name": "ubersim_parallel_v0", "is_parallelizable": True}

    def __init__(self, world="div-b", num_envs=1, *, task=None, blue="agent", yellow="agent", frame_skip=5,
                 max_episode_steps=None, camera_features=False, render_mode=None, seed=None, profile="fast",
                 physics=None, robot=None, plugin_paths=()):
        for driver in (blue, yellow):
            if driver not in ("agent", "idle", "scripted", "random"):
                raise ValueError(f"a team is 'agent', 'idle', 'scripted' or 'random', not {driver!r}")
        self._w = _Worlds(world, num_envs, blue=blue, yellow=yellow, task=task, frame_skip=frame_skip,
                          max_episode_steps=max_episode_steps, camera_features=camera_features, seed=seed,
                          profile=profile, physics=physics, robot=robot, plugin_paths=plugin_paths)
        self.render_mode = render_mode
        self.num_envs = self._w.num_envs
        slots = self._w.slots
        names = ("blue", "yellow")
        self.possible_agents = [f"{names[slots[r, 0]]}_{slots[r, 1]}" for r in self._w.controlled]
        self.agents = list(self.possible_agents)
        self._agent_team = {a: int(slots[r, 0]) for a, r in zip(self.possible_agents, self._w.controlled)}
        # Each team's view: its rows first, then the other's; yellow's turned by π.
        blue_rows = np.flatnonzero(slots[:, 0] == 0)
        yellow_rows = np.flatnonzero(slots[:, 0] == 1)
        self._order = (np.concatenate([blue_rows, yellow_rows]), np.concatenate([yellow_rows, blue_rows]))
        turn = np.array([-1.0 if f in _TURNED else 1.0 for f in self._w.features], np.float32)
        self._turn = (np.ones_like(turn), turn)
        self.agent_row = {}
        for a, r in zip(self.possible_agents, self._w.controlled):
            team = self._agent_team[a]
            self.agent_row[a] = int(np.flatnonzero(self._order[team] == r)[0])
        self._views = [np.zeros_like(self._w.obs), np.zeros_like(self._w.obs)]
        low, high = self._w.observation_bounds()
        self._observation_space = Box(low, high, dtype=np.float32)
        self._action_spaces = {a: Box(self._w.action_low[j], self._w.action_high[j], dtype=np.float32)
                               for j, a in enumerate(self.possible_agents)}
        self._w.seed(seed)

    @property
    def num_agents(self):
        return len(self.agents)

    @property
    def max_num_agents(self):
        return len(self.possible_agents)

    def observation_space(self, agent):
        """One world's observation of `agent`: robots × features."""
        return self._observation_space

    def action_space(self, agent):
        """One world's action of `agent`: the 6 components of ACTION."""
        return self._action_spaces[agent]

    def _observations(self):
        for team in (0, 1):
            np.multiply(self._w.obs[:, self._order[team]], self._turn[team], out=self._views[team])
        return {a: self._views[self._agent_team[a]] for a in self.agents}

    def reset(self, seed=None, options=None):
        """Starts a new episode in every world: (observations, infos)."""
        if seed is not None or not self._w.episodes.any():
            self._w.seed(seed)
        self._w.reset(np.arange(self.num_envs))
        return self._observations(), {a: {} for a in self.agents}

    def step(self, actions):
        """actions: agent → K × 6 (missing agents stand). Returns the five dicts of the parallel API."""
        buf = np.zeros_like(self._w.actions)
        for j, agent in enumerate(self.possible_agents):
            if agent in actions:
                buf[:, j] = actions[agent]
        return self.step_array(buf)

    def step_array(self, actions):
        """The same step with the actions of every agent in one K × agents × 6 array (no dict)."""
        reward, terminated, truncated, final, done = self._w.step(actions, autoreset=True)
        obs = self._observations()
        rewards = {a: reward[:, self._agent_team[a]] for a in self.agents}
        terminations = {a: terminated for a in self.agents}
        truncations = {a: truncated for a in self.agents}
        info = {"episode_step": self._w.episode_steps.copy()}
        if final is not None:
            info["final_obs"] = final
            info["_final_obs"] = done
        return obs, rewards, terminations, truncations, {a: info for a in self.agents}

    def render(self):
        """Every world's field as an RGB array (a tuple of K), or None without render_mode."""
        if self.render_mode != "rgb_array":
            return None
        return tuple(self._w.render(k) for k in range(self.num_envs))

    def close(self):
        """Frees the worlds."""
        self._w = None
