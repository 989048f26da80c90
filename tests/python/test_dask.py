# SPDX-License-Identifier: Apache-2.0
"""ubersim.dask: seeded worlds, sweeps and matches as Dask tasks on a LocalCluster of processes on
loopback (Debian's python3-distributed). Short worlds (1-2 s simulated on div-b): no timings."""
import io
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")

import ubersim  # noqa: E402
import ubersim.dask as ud  # noqa: E402

SOURCE = os.environ["UBERSIM_SOURCE_DIR"]
SEEDS = [5, 2, 7, 0]  # not sorted: results come in the seeds' order, not the workers'
DURATION = 1.5


@pytest.fixture(scope="module")
def client():
    """Two worker processes of one thread each on 127.0.0.1, closed (workers ended) after the module."""
    with ud.local_cluster(2) as cluster, distributed.Client(cluster) as c:
        yield c


def direct_hash(seed, duration, play="random", **world):
    """The state hash of the same world run in this process, without Dask."""
    w = ubersim.World("div-b", seed=seed, **world)
    if play == "random":
        w.random_play(seed)
    w.step(int(round(duration / w.step_seconds)))
    return w.state_hash


def test_the_package_does_not_import_dask_and_the_module_finds_the_real_dask():
    code = ("import sys, ubersim; assert 'ubersim.dask' not in sys.modules and 'distributed' not in sys.modules; "
            "import ubersim.dask, dask, distributed; assert 'distributed' not in dask.__name__; "
            "assert dask.__file__ != ubersim.dask.__file__ and hasattr(dask, 'delayed'); print('ok')")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr


def test_worlds_come_back_in_order_with_the_same_hashes_on_two_workers_one_worker_and_in_process(client):
    bar = io.StringIO()
    two = ud.run_worlds(client, "div-b", SEEDS, DURATION, progress=bar)
    assert [r.seed for r in two] == SEEDS
    assert all(r.ok for r in two), [r.error for r in two]
    assert "4/4 worlds" in bar.getvalue()
    for r in two:
        assert r.sim_time == pytest.approx(DURATION) and r.steps == 300
        assert r.params["world"] == "div-b" and r.params["play"] == "random" and r.trajectory is None
        assert r.statistics["mean_robot_speed"] > 0.1 and r.statistics["samples"] == 16
    hashes = [r.state_hash for r in two]
    assert hashes == [direct_hash(s, DURATION) for s in SEEDS]
    assert len(set(hashes)) == len(SEEDS)  # the seeds make different worlds
    with ud.local_cluster(1) as cluster, distributed.Client(cluster) as one_client:
        one = ud.run_worlds(one_client, "div-b", SEEDS, DURATION, progress=False)
    assert [r.state_hash for r in one] == hashes
    assert len({r.worker for r in one}) == 1


def test_trajectories_have_a_row_per_recording_and_do_not_change_the_world(client):
    [r] = ud.run_worlds(client, "div-b", [3], 1.0, record_every=0.25, play="idle", progress=False)
    t = r.trajectory
    assert t["time"] == pytest.approx([0.0, 0.25, 0.5, 0.75, 1.0])
    assert t["robot_pose"].shape == (5, 12, 3) and t["robot_velocity"].shape == (5, 12, 3)
    assert t["robot_present"].shape == (5, 12) and t["robot_ids"].shape == (12, 2)
    assert t["ball_position"].shape == (5, 3) and t["ball_velocity"].shape == (5, 3)
    assert r.state_hash == direct_hash(3, 1.0, play="idle")
    assert r.statistics["max_robot_speed"] < 0.05  # idle robots stand


def test_a_failing_world_comes_back_with_its_located_error_and_the_others_finish(client, tmp_path):
    with open(os.path.join(SOURCE, "models", "worlds", "div-b.yaml")) as f:
        text = f.read().replace("../", os.path.join(SOURCE, "models") + "/")
    typo = tmp_path / "typo.yaml"
    typo.write_text(text + "\nmatch:\n  referee: builtn\n")
    results = ud.sweep(client, "div-b", [{"world": typo}, {}, {"world": "no-such-world"}], seeds=[4],
                       duration=1.0, progress=False)
    bad, good, missing = results
    assert bad.error.startswith(f"ModelError: {typo}:") and "match.referee" in bad.error and bad.exit_code == 3
    assert bad.state_hash is None and not bad.ok
    assert missing.error.startswith("ModelError: no-such-world") and missing.exit_code == 3
    assert good.ok and good.state_hash == direct_hash(4, 1.0)


def test_a_sweep_over_two_physics_steps_carries_its_params_and_differs(client):
    results = ud.sweep(client, "div-b", [{"physics": {"step": 0.005}}, {"physics": {"step": 0.0025}}],
                       seeds=(1, 2), duration=1.0, progress=False)
    assert [(r.params["physics"], r.seed) for r in results] == [
        ({"step": 0.005}, 1), ({"step": 0.005}, 2), ({"step": 0.0025}, 1), ({"step": 0.0025}, 2)]
    assert all(r.ok for r in results), [r.error for r in results]
    assert [r.steps for r in results] == [200, 200, 400, 400]
    assert results[0].state_hash != results[2].state_hash
    assert results[2].state_hash == direct_hash(1, 1.0, physics={"step": 0.0025})


def forward(obs):
    """A policy: every robot of the team drives forward at 1 m/s."""
    return np.tile(np.array([1.0, 0, 0, 0, 0, 0], np.float32), (6, 1))


def test_matches_count_goals_and_repeat_in_process_and_a_failing_policy_is_reported(client):
    # 40 s: in 20 s the baseline scores on an idle team in about four seeds of ten, in 40 s in
    # nine of ten (seeds 1-10 measured), so a change that moves the play's last bits keeps a goal.
    matches = ud.evaluate_matches(client, "div-b", [1, 3], 40.0, blue="scripted", yellow="idle", progress=False)
    assert [m.seed for m in matches] == [1, 3]
    for m in matches:
        assert m.ok, m.error
        assert set(m.goals) == {"blue", "yellow"} and all(isinstance(g, int) for g in m.goals.values())
        assert m.sim_time == pytest.approx(40.0)
        here = ud.play_match(m.seed, m.params, blue="scripted", yellow="idle")
        assert (here.state_hash, here.goals, here.outs) == (m.state_hash, m.goals, m.outs)
    assert sum(m.goals["blue"] for m in matches) >= 1  # the baseline scores on an idle team
    assert all(m.goals["yellow"] == 0 for m in matches)
    policy, broken = ud.evaluate_matches(client, "div-b", [3], 2.0, blue=forward, yellow="random",
                                         progress=False) + ud.evaluate_matches(
        client, "div-b", [3], 2.0, blue=lambda obs: 1 / 0, progress=False)
    assert policy.ok and policy.params["blue"] == "policy forward"
    assert broken.error.startswith("ZeroDivisionError") and broken.state_hash is None


def test_workers_with_several_threads_are_warned_about_and_still_give_the_same_hashes():
    with ud.local_cluster(1, threads_per_worker=2) as cluster, distributed.Client(cluster) as c:
        with pytest.warns(RuntimeWarning, match="nthreads 1"):
            results = ud.run_worlds(c, "div-b", SEEDS[:2], DURATION, progress=False)
    assert [r.state_hash for r in results] == [direct_hash(s, DURATION) for s in SEEDS[:2]]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError):
            ud.run_worlds(None, "div-b", [1], 1.0, play="dance")  # refused before reaching any cluster
