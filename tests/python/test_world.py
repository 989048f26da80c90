# SPDX-License-Identifier: Apache-2.0
"""`import ubersim`: one world of the kernel's API from Python (Debian's /usr/bin/python3, pytest)."""
import os
import subprocess
import sys
import tempfile

import numpy as np
import pytest

import ubersim

SOURCE = os.environ["UBERSIM_SOURCE_DIR"]


def test_a_shipped_world_loads_by_name_and_its_state_is_the_world_files():
    world = ubersim.World("div-b", seed=3)
    assert world.name == "div-b"
    assert world.step_seconds == pytest.approx(0.005)  # the shipped worlds' fast profile
    s = world.state()
    assert s["robot_ids"].shape == (12, 2) and s["robot_ids"].dtype == np.int32
    assert s["robot_pose"].shape == (12, 3) and s["robot_pose"].dtype == np.float64
    # Blue first, by id: blue 0 stands at (-4.2, 0) facing +x, yellow 0 at (4.2, 0) facing -x.
    assert list(s["robot_ids"][0]) == [0, 0] and list(s["robot_ids"][6]) == [1, 0]
    assert s["robot_pose"][0][:2] == pytest.approx([-4.2, 0.0], abs=1e-3)
    assert abs(abs(s["robot_pose"][6][2]) - np.pi) < 1e-3
    assert s["ball_position"][:2] == pytest.approx([0.0, 0.0], abs=1e-6)
    assert s["robot_present"].all()


def test_a_robot_follows_its_velocity_command_in_its_own_frame():
    world = ubersim.World("div-b", seed=3)
    for _ in range(200):  # a team sends commands continuously; a robot without them stops
        world.command("blue", 1, vx=1.0)
        world.step()
    s = world.state()
    assert s["robot_velocity"][1][0] == pytest.approx(1.0, abs=0.05)
    assert s["robot_pose"][1][0] > -2.325 + 0.7  # it moved forward (+x) by most of a metre
    assert world.time == pytest.approx(1.0)


def test_save_and_restore_are_bit_identical_and_reset_goes_back_to_the_start():
    world = ubersim.World("div-b", seed=3)
    world.place_ball(0.5, 0.2, vx=2.0)
    world.step(50)
    snapshot = world.save()
    world.step(100)
    after = world.state_hash
    world.restore(snapshot)
    world.step(100)
    assert world.state_hash == after
    start = ubersim.World("div-b", seed=3).state_hash
    world.reset()
    assert world.time == 0.0 and world.state_hash == start


SCRIPT = """
import sys, numpy as np, ubersim
world = ubersim.World("div-b", seed=int(sys.argv[1]))
rng = np.random.default_rng(5)
for step in range(300):
    for i in range(6):
        world.command("yellow", i, vx=rng.uniform(-2, 2), vy=rng.uniform(-2, 2), angular=rng.uniform(-3, 3))
    world.step()
print(world.state_hash)
"""


def run_in_new_process(seed):
    out = subprocess.run([sys.executable, "-c", SCRIPT, str(seed)], capture_output=True, text=True, check=True,
                         env=dict(os.environ))
    return int(out.stdout.strip())


def test_the_same_seed_gives_the_same_trajectory_in_two_processes():
    a, b = run_in_new_process(11), run_in_new_process(11)
    assert a == b


def test_errors_carry_the_command_lines_text_and_exit_code():
    with pytest.raises(ubersim.ModelError) as missing:
        ubersim.World("/nonexistent/world.yaml")
    assert "cannot open file" in str(missing.value)
    assert missing.value.exit_code == 3
    # A typo in a world file: file:line:column and the key, as `ubersim validate` says it.
    with open(os.path.join(SOURCE, "models", "worlds", "div-b.yaml")) as f:
        text = f.read().replace("../", os.path.join(SOURCE, "models") + "/")
    with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as f:
        f.write(text + "\nmatch:\n  referee: builtn\n")
        typo = f.name
    try:
        with pytest.raises(ubersim.ModelError) as bad:
            ubersim.World(typo)
        message = str(bad.value)
        assert message.startswith(typo + ":") and "match.referee" in message and "builtin" in message
    finally:
        os.unlink(typo)
    with pytest.raises(ubersim.SnapshotError):
        ubersim.World("div-b").restore(b"not a snapshot")
    with pytest.raises(ValueError):
        ubersim.World("div-b").command("green", 0)


def test_the_stubs_name_every_public_member_of_the_module():
    # An editor completes from __init__.pyi: it must list what the module really has.
    stub = open(os.path.join(os.path.dirname(ubersim.__file__), "__init__.pyi")).read()
    for cls in (ubersim.World, ubersim.VectorEnv, ubersim.Env, ubersim.ParallelEnv):
        body = stub.split(f"class {cls.__name__}")[1].split("\nclass ")[0]
        for name in [n for n in dir(cls) if not n.startswith("_")]:
            if callable(getattr(cls, name)) or isinstance(getattr(cls, name), property):
                assert f"def {name}(" in body, (cls.__name__, name)
    for name in ubersim.__all__:
        kind = type(getattr(ubersim, name)).__name__
        if kind == "module":
            assert f"import {name} as {name}" in stub, name
        elif kind == "function":
            assert f"import {name} as {name}" in stub, name
        else:
            assert f"class {name}" in stub, name
