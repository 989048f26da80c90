# SPDX-License-Identifier: Apache-2.0
# ubersim.VectorEnv / Env / ParallelEnv: the Gymnasium and PettingZoo contracts checked as their
# environment checkers would (Debian has neither package), the observation layout against the
# kernel's own state, actions, auto-reset, seeding across processes, the tasks, and threads.
import os
import subprocess
import sys
import threading

import numpy as np
import pytest

import ubersim
from ubersim import tasks
from ubersim.env import ACTION, FEATURES

F = {name: i for i, name in enumerate(FEATURES)}
A = {name: i for i, name in enumerate(ACTION)}


def in_box(space, x):
    return x.shape == space.shape and x.dtype == space.dtype and space.contains(x)


def test_vector_env_follows_the_gymnasium_vector_contract():
    env = ubersim.VectorEnv("div-b", 3, task=tasks.GoToBall(), opponent="scripted", seed=4)
    k = env.num_envs
    assert k == 3
    assert env.single_observation_space.shape == (12, 16) and env.single_observation_space.dtype == np.float32
    assert env.observation_space.shape == (k, 12, 16)
    assert env.single_action_space.shape == (6, 6) and env.action_space.shape == (k, 6, 6)
    assert np.array_equal(env.action_space.low[1], env.single_action_space.low)
    obs, info = env.reset(seed=4)
    assert isinstance(info, dict) and in_box(env.observation_space, obs)
    for _ in range(5):
        action = env.action_space.sample()
        assert in_box(env.action_space, action)
        obs, reward, terminated, truncated, info = env.step(action)
        assert in_box(env.observation_space, obs)
        assert reward.shape == (k,) and np.issubdtype(reward.dtype, np.floating)
        assert terminated.shape == (k,) and terminated.dtype == bool
        assert truncated.shape == (k,) and truncated.dtype == bool
        assert isinstance(info, dict)
    assert env.render() is None
    with pytest.raises(ValueError):
        env.step(np.zeros((k, 5, 6), np.float32))  # one robot short
    env.close()


def test_env_follows_the_gymnasium_env_contract_and_renders():
    env = ubersim.Env("div-b", task=tasks.EmptyGoal(), render_mode="rgb_array", seed=1)
    obs, info = env.reset(seed=1)
    assert in_box(env.observation_space, obs) and isinstance(info, dict)
    again, _ = env.reset(seed=1)
    assert np.array_equal(obs, again), "the same seed must give the same start"
    other, _ = env.reset(seed=2)
    assert not np.array_equal(obs, other), "another seed must give another start"
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    assert in_box(env.observation_space, obs)
    assert isinstance(reward, float) and isinstance(terminated, bool) and isinstance(truncated, bool)
    image = env.render()
    assert image.dtype == np.uint8 and image.ndim == 3 and image.shape[2] == 3 and image.shape[1] == 640
    env.close()


def test_the_observation_is_the_kernels_state():
    env = ubersim.VectorEnv("div-b", 2, opponent="random", seed=9)
    env.reset(seed=9)
    for _ in range(20):
        obs, *_ = env.step(env.action_space.sample())
    # World 1's state, restored into a world of the kernel's own API, read back through state().
    world = ubersim.World("div-b", profile="fast")
    world.restore(env.worlds.save(1))
    s = world.state()
    rows = obs[1]
    assert [tuple(r) for r in env.slots] == [tuple(r) for r in s["robot_ids"]]
    present = s["robot_present"]
    assert np.array_equal(rows[:, F["present"]] > 0.5, present)
    np.testing.assert_allclose(rows[present, F["x"]], s["robot_pose"][present, 0], atol=1e-5)
    np.testing.assert_allclose(rows[present, F["y"]], s["robot_pose"][present, 1], atol=1e-5)
    np.testing.assert_allclose(rows[present, F["cos_yaw"]], np.cos(s["robot_pose"][present, 2]), atol=1e-5)
    np.testing.assert_allclose(rows[present, F["sin_yaw"]], np.sin(s["robot_pose"][present, 2]), atol=1e-5)
    np.testing.assert_allclose(rows[present, F["vx"]], s["robot_velocity"][present, 0], atol=1e-4)
    np.testing.assert_allclose(rows[present, F["omega"]], s["robot_velocity"][present, 2], atol=1e-4)
    for c, name in enumerate(("ball_x", "ball_y", "ball_z")):
        np.testing.assert_allclose(rows[:, F[name]], s["ball_position"][c], atol=1e-5)
    np.testing.assert_allclose(rows[:, F["ball_vx"]], s["ball_velocity"][0], atol=1e-4)
    assert np.abs(rows[present, F["vx"]]).max() > 0.05, "random play moves the robots"


def test_actions_move_the_robot_in_its_own_frame():
    # Blue 0 alone, facing +y: "forward" must move it along +y in the field frame.
    class Facing(tasks.Task):
        def start(self, rng, indices, env):
            s = self._empty_start(env, len(indices))
            s["robot_pose"][:, 0] = (0.0, 0.0, np.pi / 2)
            s["robot_present"][:, 0] = True
            s["ball"][:, :3] = (2.0, 2.0, tasks.BALL_RADIUS)
            return s

    env = ubersim.VectorEnv("div-b", 1, task=Facing(), seed=0)
    obs, _ = env.reset(seed=0)
    assert obs[0, :, F["present"]].sum() == 1
    action = np.zeros(env.action_space.shape, np.float32)
    action[0, 0, A["forward"]] = 1.0
    for _ in range(40):  # 1 s
        obs, *_ = env.step(action)
    assert obs[0, 0, F["y"]] > 0.5 and abs(obs[0, 0, F["x"]]) < 0.1
    assert obs[0, 0, F["vy"]] > 0.7
    # Actions outside the space are clipped to it (the robot's limits).
    action[0, 0, A["forward"]] = 100.0
    for _ in range(80):
        obs, *_ = env.step(action)
    assert obs[0, 0, F["vy"]] <= env.single_action_space.high[0, 0] + 0.1


def test_worlds_reset_on_their_own_with_the_final_observation():
    env = ubersim.VectorEnv("div-b", 2, task=tasks.GoToBall(), max_episode_steps=3, seed=5)
    obs, info = env.reset(seed=5)
    first = obs.copy()
    for step in range(3):
        obs, reward, terminated, truncated, info = env.step(np.zeros(env.action_space.shape, np.float32))
    assert truncated.all() and not terminated.any()
    assert info["_final_obs"].all() and info["final_obs"].shape == obs.shape
    assert np.array_equal(info["episode"], [2, 2]) and np.array_equal(info["episode_step"], [0, 0])
    # The new episode starts elsewhere (the task draws again), the final observation is the old one.
    assert not np.array_equal(obs, first)
    assert np.abs(info["final_obs"][:, 0, F["x"]] - first[:, 0, F["x"]]).max() < 0.3


def trajectory_hashes(seed, steps=30):
    env = ubersim.VectorEnv("div-b", 3, task=tasks.GoToBall(), opponent="scripted", max_episode_steps=12, seed=seed)
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(steps):
        obs, *_ = env.step(rng.uniform(env.action_space.low, env.action_space.high).astype(np.float32))
        out.append([env.worlds.state_hash(k) for k in range(env.num_envs)])
    return out, obs


def test_the_same_seeds_give_bit_identical_trajectories_in_one_process_and_across_processes():
    a, obs_a = trajectory_hashes(11)
    b, obs_b = trajectory_hashes(11)
    assert a == b and np.array_equal(obs_a, obs_b)
    c, _ = trajectory_hashes(12)
    assert c != a
    code = ("import sys, json; sys.path.insert(0, sys.argv[1]); import test_env; "
            "print(json.dumps(test_env.trajectory_hashes(11)[0]))")
    out = subprocess.run([sys.executable, "-c", code, os.path.dirname(__file__)], capture_output=True, text=True,
                         check=True, env=dict(os.environ))
    import json
    assert json.loads(out.stdout.strip().splitlines()[-1]) == a


def test_go_to_ball_is_solved_by_a_simple_controller():
    # A proportional controller written against the documented layout: it must get the task's
    # success (10) within the episode, so the task, the observation and the actions agree.
    env = ubersim.VectorEnv("div-b", 4, task=tasks.GoToBall(), seed=3)
    obs, _ = env.reset(seed=3)
    successes = np.zeros(env.num_envs, bool)
    for _ in range(tasks.GoToBall.max_episode_steps):
        r = obs[:, 0]
        dx, dy = r[:, F["ball_x"]] - r[:, F["x"]], r[:, F["ball_y"]] - r[:, F["y"]]
        c, s = r[:, F["cos_yaw"]], r[:, F["sin_yaw"]]
        forward, left = c * dx + s * dy, -s * dx + c * dy  # the ball in the robot's frame
        bearing, distance = np.arctan2(left, forward), np.hypot(dx, dy)
        action = np.zeros(env.action_space.shape, np.float32)
        action[:, 0, A["forward"]] = np.minimum(1.5, 1.5 * distance) * np.clip(np.cos(bearing), 0, 1) ** 4
        action[:, 0, A["angular"]] = np.clip(5.0 * bearing, -6.0, 6.0)  # face the ball, then drive at it
        action[:, 0, A["dribbler"]] = 100.0
        obs, reward, terminated, truncated, info = env.step(action)
        successes |= terminated & (reward > 9.0)  # 10 for the success, less what the last step gave back
        if successes.all():
            break
    assert successes.all(), successes


def test_a_ball_into_the_goal_ends_empty_goal_with_the_goal_reward():
    class Shot(tasks.EmptyGoal):
        def start(self, rng, indices, env):
            s = super().start(rng, indices, env)
            s["ball"][:] = (0.5 * env.field["field_length"] - 0.6, 0.0, tasks.BALL_RADIUS, 3.0, 0.0, 0.0)
            s["robot_pose"][:, 0, :2] = (-1.0, 2.0)  # out of the ball's way
            return s

    env = ubersim.VectorEnv("div-b", 2, task=Shot(), seed=0)
    env.reset(seed=0)
    for _ in range(40):
        obs, reward, terminated, truncated, info = env.step(np.zeros(env.action_space.shape, np.float32))
        if terminated.any():
            break
    assert terminated.all() and (reward > 9.5).all(), (reward, terminated)  # 10, less the last step's shaping


@pytest.mark.parametrize("task, blue, yellow", [(tasks.GoToBall(), 1, 0), (tasks.EmptyGoal(), 1, 0),
                                                (tasks.StaticDefenders(defenders=3), 1, 4), (tasks.Pass(), 2, 0)])
def test_the_shipped_tasks_start_their_robots_on_the_field(task, blue, yellow):
    env = ubersim.VectorEnv("div-b", 8, task=task, seed=2)
    obs, _ = env.reset(seed=2)
    present = obs[:, :, F["present"]] > 0.5
    assert (present[:, env.slots[:, 0] == 0].sum(axis=1) == blue).all()
    assert (present[:, env.slots[:, 0] == 1].sum(axis=1) == yellow).all()
    half_x, half_y = 0.5 * env.field["field_length"], 0.5 * env.field["field_width"]
    assert (np.abs(obs[:, :, F["x"]][present]) < half_x).all() and (np.abs(obs[:, :, F["y"]][present]) < half_y).all()
    assert (np.abs(obs[:, 0, F["ball_x"]]) < half_x).all()
    assert len({tuple(np.round(obs[k, 0, [F["ball_x"], F["ball_y"]]], 3)) for k in range(8)}) == 8, "starts differ"
    for _ in range(3):
        obs, reward, *_ = env.step(env.action_space.sample())
        assert np.isfinite(reward).all()


def test_a_plain_callable_is_a_task():
    calls = []

    def task(obs, actions, env):
        calls.append(obs.shape)
        return obs[:, 0, F["x"]].astype(np.float64), np.zeros(len(obs), bool)

    env = ubersim.VectorEnv("div-b", 2, task=task, seed=0)
    env.reset(seed=0)
    obs, reward, _, _, info = env.step(np.zeros(env.action_space.shape, np.float32))
    assert calls == [(2, 12, 16)]
    np.testing.assert_allclose(reward, obs[:, 0, F["x"]], rtol=1e-6)
    np.testing.assert_allclose(info["team_reward"][:, 1], -reward)


def test_opponents_scripted_move_idle_stand():
    def yellow_moved(opponent):
        env = ubersim.VectorEnv("div-b", 1, opponent=opponent, seed=0)
        obs, _ = env.reset(seed=0)
        start = obs[0, env.slots[:, 0] == 1, :3].copy()
        for _ in range(60):
            obs, *_ = env.step(np.zeros(env.action_space.shape, np.float32))
        return np.abs(obs[0, env.slots[:, 0] == 1, 1:3] - start[:, 1:3]).max()

    assert yellow_moved("idle") < 0.01
    assert yellow_moved("scripted") > 0.3


def test_camera_features_report_what_the_cameras_saw():
    env = ubersim.VectorEnv("div-b", 1, camera_features=True, seed=0)
    assert env.features == FEATURES and env.single_observation_space.shape == (12, 24)
    obs, _ = env.reset(seed=0)
    for _ in range(10):
        obs, *_ = env.step(np.zeros(env.action_space.shape, np.float32))
    rows = obs[0]
    seen = rows[:, F["seen"]] > 0.5
    assert seen.sum() >= 10, "most robots are reported within 25 ms at 60+ Hz"
    error = np.hypot(rows[seen, F["seen_x"]] - rows[seen, F["x"]], rows[seen, F["seen_y"]] - rows[seen, F["y"]])
    assert error.max() < 0.05 and error.max() > 0.0, "noisy reports near the truth"
    assert rows[0, F["ball_seen"]] == 1.0
    assert abs(rows[0, F["ball_seen_x"]] - rows[0, F["ball_x"]]) < 0.05


def test_parallel_env_follows_the_parallel_contract_both_teams_as_agents():
    env = ubersim.ParallelEnv("div-b", 2, seed=3)
    assert env.possible_agents[:2] == ["blue_0", "blue_1"] and env.possible_agents[-1] == "yellow_5"
    assert env.num_agents == 12 == env.max_num_agents
    observations, infos = env.reset(seed=3)
    assert set(observations) == set(env.agents) == set(infos)
    for agent in env.agents:
        assert observations[agent].shape == (2,) + env.observation_space(agent).shape
        assert env.action_space(agent).shape == (6,)
    actions = {a: np.stack([env.action_space(a).sample() for _ in range(2)]) for a in env.agents}
    observations, rewards, terminations, truncations, infos = env.step(actions)
    for d in (observations, rewards, terminations, truncations, infos):
        assert set(d) == set(env.agents)
    assert rewards["blue_0"].shape == (2,) and terminations["yellow_3"].dtype == bool
    # Each team's view: its own rows first, the field turned by π for yellow.
    blue, yellow = observations["blue_0"], observations["yellow_0"]
    assert env.agent_row["yellow_0"] == 0 and env.agent_row["blue_2"] == 2
    turned = np.array([-1.0 if f in ("x", "y", "cos_yaw", "sin_yaw", "vx", "vy", "ball_x", "ball_y", "ball_vx",
                                     "ball_vy") else 1.0 for f in env.features], np.float32)
    np.testing.assert_array_equal(yellow[:, :6], blue[:, 6:] * turned)
    np.testing.assert_array_equal(yellow[:, 6:], blue[:, :6] * turned)
    # The dict form and the array form are the same step.
    array = np.stack([actions[a] for a in env.possible_agents], axis=1)
    one = ubersim.ParallelEnv("div-b", 2, seed=3)
    one.reset(seed=3)
    one.step_array(array)
    assert [one.worlds.state_hash(k) for k in range(2)] == [env.worlds.state_hash(k) for k in range(2)]


def test_two_threads_stepping_worlds_get_what_one_thread_gets():
    # ODE's generator is process-wide: the module serialises the worlds of two threads.
    def run(out, seed):
        world = ubersim.World("div-b", seed=seed)
        world.random_play(seed)
        world.step(400)
        out[seed] = world.state_hash

    alone = {}
    run(alone, 1)
    run(alone, 2)
    together = {}
    threads = [threading.Thread(target=run, args=(together, s)) for s in (1, 2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert together == alone


def test_bad_arguments_are_value_errors():
    with pytest.raises(ValueError):
        ubersim.VectorEnv("div-b", 0)
    with pytest.raises(ValueError):
        ubersim.VectorEnv("div-b", 1, opponent="clever")
    with pytest.raises(ValueError):
        ubersim.VectorEnv("div-b", 1, controlled="green")
    with pytest.raises(ValueError, match="physics"):
        ubersim.VectorEnv("div-b", 1, physics={"stepp": 0.001})
    with pytest.raises(ValueError, match="profile"):
        ubersim.VectorEnv("div-b", 1, profile="quick")
    with pytest.raises(ubersim.ModelError):
        ubersim.VectorEnv("/nonexistent/world.yaml", 1)


def test_fast_is_the_default_profile_and_precise_one_argument_away():
    assert ubersim.VectorEnv("div-b", 1).worlds.profile == "fast"
    precise = ubersim.VectorEnv("div-b", 1, profile="precise")
    assert precise.worlds.profile == "precise" and precise.dt == pytest.approx(5 * 0.001)
    assert ubersim.VectorEnv("div-b", 1).dt == pytest.approx(5 * 0.005)


def test_observations_are_copies_unless_asked_for_the_buffer():
    env = ubersim.VectorEnv("div-b", 2, opponent="random", seed=0)
    first, _ = env.reset(seed=0)
    kept = first.copy()
    second, *_ = env.step(np.zeros(env.action_space.shape, np.float32))
    assert np.array_equal(first, kept) and not np.array_equal(first, second)
    shared = ubersim.VectorEnv("div-b", 2, opponent="random", seed=0, copy=False)
    first, _ = shared.reset(seed=0)
    second, *_ = shared.step(np.zeros(shared.action_space.shape, np.float32))
    assert first is second and np.array_equal(first, second)


def test_after_a_restore_the_actions_reach_the_robots_the_snapshot_has_on_the_field():
    full = ubersim.VectorEnv("div-b", 1, seed=0)  # every robot on the field
    full.reset(seed=0)
    alone = ubersim.VectorEnv("div-b", 1, task=tasks.GoToBall(), seed=0)  # blue 0 alone
    obs, _ = alone.reset(seed=0)
    assert obs[0, 1, F["present"]] == 0.0
    alone.worlds.restore(0, full.worlds.save(0))
    action = np.zeros(alone.action_space.shape, np.float32)
    action[0, 1, A["forward"]] = 1.0  # blue 1, off the field before the restore
    for _ in range(20):
        obs, *_ = alone.step(action)
    assert obs[0, 1, F["present"]] == 1.0 and np.hypot(obs[0, 1, F["vx"]], obs[0, 1, F["vy"]]) > 0.5
