# SPDX-License-Identifier: Apache-2.0
"""Tasks: where an episode starts, its reward and when it ends (docs/python.md, Tasks).

A task is any object with evaluate(obs, actions, env) → (reward, terminated), and optionally
start(rng, indices, env) → dict or None and begin(obs, indices, env); a plain callable with
evaluate's signature is a task too. Everything is vectorised over the K worlds (numpy, no loop
over worlds or robots). Rewards are the blue team's (K) or per team (K × 2: blue, yellow).
Blue attacks the goal at +x. The shipped tasks cover rSoccer's SSL set:

- GoToBall: one robot goes to the ball and dribbles it (rSoccer's SSLGoToBall);
- EmptyGoal: one robot scores on an empty goal (SSLGoToBallShoot);
- StaticDefenders: the same past defenders that stand still (SSLStaticDefenders);
- Pass: two robots pass the ball between them (SSLPassEndurance).
"""
import numpy as np

from .env import FEATURES

_F = {name: i for i, name in enumerate(FEATURES)}
BALL_RADIUS = 0.0215  # m, the league's ball (physics.md)


class Task:
    """Base of the shipped tasks: no reward, never ends, the world file's start."""

    #: Episodes are truncated after this many env steps (the env's max_episode_steps overrides it).
    max_episode_steps = None

    def start(self, rng, indices, env):
        """Where the worlds `indices` start (robot_pose n × robots × 3, robot_present, ball n × 6), or None."""
        return None

    def begin(self, obs, indices, env):
        """Called with the first observation of the worlds `indices`."""

    def evaluate(self, obs, actions, env):
        """(reward, terminated) of every world after a step."""
        return np.zeros(len(obs)), np.zeros(len(obs), bool)

    # Helpers for the shipped tasks.
    def _per_world(self, k, **dtypes):
        """Per-world state arrays as attributes (`_name`), made again when the number of worlds changes."""
        for name, dtype in dtypes.items():
            current = getattr(self, "_" + name, None)
            if current is None or len(current) != k:
                setattr(self, "_" + name, np.zeros(k, dtype))

    @staticmethod
    def _rows(env, team):
        return np.flatnonzero(env.slots[:, 0] == team)

    @staticmethod
    def _uniform_points(rng, n, half_x, half_y, x_range=None):
        lo, hi = x_range if x_range is not None else (-half_x, half_x)
        return np.stack([rng.uniform(lo, hi, n), rng.uniform(-half_y, half_y, n)], axis=1)

    @staticmethod
    def _empty_start(env, n):
        return {"robot_pose": np.zeros((n, env.robots, 3)), "robot_present": np.zeros((n, env.robots), bool),
                "ball": np.zeros((n, 6))}

    @staticmethod
    def _ball_events(obs, field):
        """Per world: blue scored, yellow scored, the ball out elsewhere (over a line, not a goal)."""
        x, y, z = obs[:, 0, _F["ball_x"]], obs[:, 0, _F["ball_y"]], obs[:, 0, _F["ball_z"]]
        half_length, half_width = 0.5 * field["field_length"], 0.5 * field["field_width"]
        in_mouth = (np.abs(y) < 0.5 * field["goal_width"]) & (z < field["goal_height"])
        blue_goal = (x > half_length) & in_mouth
        yellow_goal = (x < -half_length) & in_mouth
        out = ((np.abs(x) > half_length) | (np.abs(y) > half_width)) & ~blue_goal & ~yellow_goal
        return blue_goal, yellow_goal, out


class GoToBall(Task):
    """One blue robot goes to the ball and dribbles it: reward the metres it closes on the ball,
    +10 once it has held the ball at its dribbler for `hold_steps` env steps running (ends)."""

    max_episode_steps = 400

    def __init__(self, hold_steps=10, margin=0.3):
        self.hold_steps = hold_steps
        self.margin = margin

    def start(self, rng, indices, env):
        n = len(indices)
        s = self._empty_start(env, n)
        row = self._rows(env, 0)[0]
        half_x = 0.5 * env.field["field_length"] - self.margin
        half_y = 0.5 * env.field["field_width"] - self.margin
        robot = self._uniform_points(rng, n, half_x, half_y)
        ball = self._uniform_points(rng, n, half_x, half_y)
        for _ in range(20):  # the ball at least 0.4 m from the robot: redraw the few too close
            close = np.linalg.norm(ball - robot, axis=1) < 0.4
            if not close.any():
                break
            ball[close] = self._uniform_points(rng, int(close.sum()), half_x, half_y)
        s["robot_pose"][:, row, :2] = robot
        s["robot_pose"][:, row, 2] = rng.uniform(-np.pi, np.pi, n)
        s["robot_present"][:, row] = True
        s["ball"][:, :2] = ball
        s["ball"][:, 2] = BALL_RADIUS
        return s

    def _robot_ball_distance(self, obs, env):
        row = self._rows(env, 0)[0]
        r = obs[:, row]
        return np.hypot(r[:, _F["x"]] - r[:, _F["ball_x"]], r[:, _F["y"]] - r[:, _F["ball_y"]])

    def begin(self, obs, indices, env):
        self._per_world(obs.shape[0], distance=np.float64, held=np.int64)
        self._distance[indices] = self._robot_ball_distance(obs, env)[indices]
        self._held[indices] = 0

    def evaluate(self, obs, actions, env):
        row = self._rows(env, 0)[0]
        distance = self._robot_ball_distance(obs, env)
        reward = self._distance - distance
        self._distance = distance
        contact = obs[:, row, _F["ball_contact"]] > 0.5
        self._held = np.where(contact, self._held + 1, 0)
        done = self._held >= self.hold_steps
        reward = reward + 10.0 * done
        return reward, done


class EmptyGoal(Task):
    """One blue robot and the ball in the half it attacks, nobody in goal: +10 for a goal (ends),
    −1 when the ball goes out elsewhere (ends), and on the way the metres the ball gains towards
    the goal's centre plus a tenth of those the robot closes on the ball."""

    max_episode_steps = 400
    defenders = 0

    def __init__(self, margin=0.3):
        self.margin = margin

    def _place_defenders(self, rng, s, env, n):
        """EmptyGoal has none; StaticDefenders puts its defenders here."""

    def start(self, rng, indices, env):
        n = len(indices)
        s = self._empty_start(env, n)
        row = self._rows(env, 0)[0]
        half_x = 0.5 * env.field["field_length"] - self.margin
        half_y = 0.5 * env.field["field_width"] - self.margin
        s["robot_pose"][:, row, :2] = self._uniform_points(rng, n, half_x, half_y, (0.0, 0.5 * half_x))
        s["robot_pose"][:, row, 2] = rng.uniform(-np.pi, np.pi, n)
        s["robot_present"][:, row] = True
        s["ball"][:, :2] = self._uniform_points(rng, n, half_x, half_y, (0.5, half_x - env.field["penalty_area_depth"]))
        s["ball"][:, 2] = BALL_RADIUS
        self._place_defenders(rng, s, env, n)
        return s

    def _distances(self, obs, env):
        row = self._rows(env, 0)[0]
        r = obs[:, row]
        goal_x = 0.5 * env.field["field_length"]
        ball_to_goal = np.hypot(goal_x - r[:, _F["ball_x"]], r[:, _F["ball_y"]])
        robot_to_ball = np.hypot(r[:, _F["x"]] - r[:, _F["ball_x"]], r[:, _F["y"]] - r[:, _F["ball_y"]])
        return ball_to_goal, robot_to_ball

    def begin(self, obs, indices, env):
        self._per_world(obs.shape[0], ball_to_goal=np.float64, robot_to_ball=np.float64)
        ball_to_goal, robot_to_ball = self._distances(obs, env)
        self._ball_to_goal[indices] = ball_to_goal[indices]
        self._robot_to_ball[indices] = robot_to_ball[indices]

    def evaluate(self, obs, actions, env):
        ball_to_goal, robot_to_ball = self._distances(obs, env)
        reward = (self._ball_to_goal - ball_to_goal) + 0.1 * (self._robot_to_ball - robot_to_ball)
        self._ball_to_goal, self._robot_to_ball = ball_to_goal, robot_to_ball
        goal, own_goal, out = self._ball_events(obs, env.field)
        reward = reward + 10.0 * goal - 1.0 * (out | own_goal)
        return reward, goal | own_goal | out


class StaticDefenders(EmptyGoal):
    """EmptyGoal past yellow defenders that stand still (run it with opponent='idle'): a keeper on
    the goal line and `defenders` more between the ball and the goal."""

    def __init__(self, defenders=3, margin=0.3):
        super().__init__(margin)
        self.defenders = defenders

    def _place_defenders(self, rng, s, env, n):
        yellow = self._rows(env, 1)
        if len(yellow) < self.defenders + 1:
            raise ValueError(f"StaticDefenders needs {self.defenders + 1} yellow robots; the world has {len(yellow)}")
        goal_x = 0.5 * env.field["field_length"]
        keeper = yellow[0]
        s["robot_pose"][:, keeper, 0] = goal_x - 0.15
        s["robot_pose"][:, keeper, 1] = rng.uniform(-0.3, 0.3, n) * env.field["goal_width"]
        s["robot_pose"][:, keeper, 2] = np.pi
        s["robot_present"][:, keeper] = True
        ball = s["ball"][:, :2]
        for j, row in enumerate(yellow[1:self.defenders + 1]):  # a loop over the few defenders, not the worlds
            along = rng.uniform(0.3, 0.8, n)  # the fraction of the way from the ball to the goal
            s["robot_pose"][:, row, 0] = ball[:, 0] + along * (goal_x - ball[:, 0])
            s["robot_pose"][:, row, 1] = ball[:, 1] * (1 - along) + rng.uniform(-0.6, 0.6, n)
            s["robot_pose"][:, row, 2] = np.pi
            s["robot_present"][:, row] = True


class Pass(Task):
    """Two blue robots pass the ball between them: +1 each time the ball, kicked by one, reaches
    the other's dribbler; ends when the ball leaves the field or rests away from both for
    `idle_steps` env steps."""

    max_episode_steps = 1200

    def __init__(self, distance=(1.5, 3.0), idle_steps=80):
        self.distance = distance
        self.idle_steps = idle_steps

    def start(self, rng, indices, env):
        n = len(indices)
        s = self._empty_start(env, n)
        a, b = self._rows(env, 0)[:2]
        half_x, half_y = 0.5 * env.field["field_length"] - 1.0, 0.5 * env.field["field_width"] - 1.0
        centre = self._uniform_points(rng, n, half_x - 1.5, half_y - 1.5)
        heading = rng.uniform(-np.pi, np.pi, n)
        spread = rng.uniform(*self.distance, n)
        direction = np.stack([np.cos(heading), np.sin(heading)], axis=1)
        s["robot_pose"][:, a, :2] = centre - 0.5 * spread[:, None] * direction
        s["robot_pose"][:, a, 2] = heading
        s["robot_pose"][:, b, :2] = centre + 0.5 * spread[:, None] * direction
        s["robot_pose"][:, b, 2] = heading + np.pi
        s["robot_present"][:, [a, b]] = True
        # The ball just in front of robot a's dribbler.
        s["ball"][:, :2] = s["robot_pose"][:, a, :2] + 0.11 * direction
        s["ball"][:, 2] = BALL_RADIUS
        return s

    def begin(self, obs, indices, env):
        self._per_world(obs.shape[0], holder=np.int64, idle=np.int64)
        self._holder[indices] = 0  # robot a has the ball
        self._idle[indices] = 0

    def evaluate(self, obs, actions, env):
        a, b = self._rows(env, 0)[:2]
        at_a = obs[:, a, _F["ball_contact"]] > 0.5
        at_b = obs[:, b, _F["ball_contact"]] > 0.5
        received = (at_b & (self._holder == 0)) | (at_a & (self._holder == 1))
        self._holder = np.where(at_a, 0, np.where(at_b, 1, self._holder))
        speed = np.hypot(obs[:, 0, _F["ball_vx"]], obs[:, 0, _F["ball_vy"]])
        self._idle = np.where((speed < 0.05) & ~at_a & ~at_b, self._idle + 1, 0)
        goal, own_goal, out = self._ball_events(obs, env.field)
        return received.astype(np.float64), out | goal | own_goal | (self._idle >= self.idle_steps)
