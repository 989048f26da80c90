#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""What ubersim.VectorEnv costs over the kernel stepping the same worlds (docs/performance.md).

Both sides run the same K worlds with the bench's random play driving every robot (the work
`ubersim bench` measures), with the same seeds, so their final state hashes must agree — the
script checks it (exit 1 otherwise):
  kernel: K ubersim.World objects, each stepped by one C++ call per env step's physics steps
          (no observations: `ubersim bench`'s loop);
  env:    one ubersim.VectorEnv(controlled='none', opponent='random') of K worlds, stepped with
          an action array, its observations written every env step, auto-reset and task off.
It prints env steps per second, µs per physics step and the env's overhead over the kernel.
--instructions counts both under callgrind (Debian's valgrind): two runs per side, of
--instructions-durations simulated seconds; the difference of the totals over the env steps
between them is the instructions per env step, free of start-up and of the machine's noise.

  PYTHONPATH=build/python /usr/bin/python3 tools/env_bench.py --world div-a --num-envs 8
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np


def run(side, world, robot, num_envs, duration, frame_skip, seed):
    """Steps `side` for `duration` simulated seconds; returns (wall s, env steps, physics steps, hashes)."""
    import ubersim
    from ubersim.env import _episode_seed

    env = ubersim.VectorEnv(world, num_envs, controlled="none", opponent="random", frame_skip=frame_skip,
                            robot=robot, seed=seed)
    env_steps = int(round(duration / env.dt))
    if side == "env":
        env.reset(seed=seed)
        actions = np.zeros(env.action_space.shape, np.float32)
        start = time.perf_counter()
        for _ in range(env_steps):
            env.step(actions)
        wall = time.perf_counter() - start
        hashes = [env.worlds.state_hash(k) for k in range(num_envs)]
    else:
        # The worlds the env's reset builds: world k with its first episode's seed, random play on.
        seeds = [_episode_seed(seed + k, 0) for k in range(num_envs)]
        env.close()
        worlds = [ubersim.World(world, seed=s, profile="fast", robot=robot) for s in seeds]
        for w, s in zip(worlds, seeds):
            w.random_play(s)
        start = time.perf_counter()
        for _ in range(env_steps):
            for w in worlds:
                w.step(frame_skip)
        wall = time.perf_counter() - start
        hashes = [w.state_hash for w in worlds]
    return wall, env_steps, env_steps * frame_skip * num_envs, hashes


def callgrind_total(args, side, duration):
    """The instructions callgrind counts for one run of this script."""
    with tempfile.TemporaryDirectory() as folder:
        out = os.path.join(folder, "callgrind.out")
        command = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", sys.executable, __file__,
                   "--side", side, "--world", args.world, "--num-envs", str(args.num_envs), "--duration",
                   str(duration), "--frame-skip", str(args.frame_skip), "--seed", str(args.seed)]
        if args.robot:
            command += ["--robot", args.robot]
        subprocess.run(command, check=True, capture_output=True, text=True)
        with open(out) as f:
            for line in f:
                match = re.match(r"(summary|totals):\s+(\d+)", line)
                if match:
                    return int(match.group(2))
    raise RuntimeError("callgrind wrote no total")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--world", default="div-b")
    parser.add_argument("--robot", help="a robot model file for every robot (e.g. the omni_force robot)")
    parser.add_argument("--num-envs", type=int, default=8)
    parser.add_argument("--duration", type=float, default=10.0, help="simulated seconds per world")
    parser.add_argument("--frame-skip", type=int, default=5)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--side", choices=("env", "kernel", "both"), default="both")
    parser.add_argument("--repeat", type=int, default=3,
                        help="runs of each side, alternated; the fastest of each counts (the machine's noise only slows)")
    parser.add_argument("--instructions", action="store_true")
    parser.add_argument("--instructions-durations", default="1,3")
    args = parser.parse_args()

    if args.side != "both":  # one side alone (what callgrind runs)
        run(args.side, args.world, args.robot, args.num_envs, args.duration, args.frame_skip, args.seed)
        return 0
    runs = {"kernel": [], "env": []}
    for _ in range(args.repeat):
        for side in ("kernel", "env"):
            runs[side].append(run(side, args.world, args.robot, args.num_envs, args.duration, args.frame_skip,
                                  args.seed))
    kernel, env = (min(runs[side], key=lambda r: r[0]) for side in ("kernel", "env"))
    robot = os.path.basename(args.robot) if args.robot else "the world's robots"
    print(f"{args.world}, {robot}, {args.num_envs} worlds, frame_skip {args.frame_skip}, "
          f"{args.duration:g} s simulated each, random play; fastest of {args.repeat} alternated runs")
    for name, (wall, env_steps, physics_steps, _) in (("kernel", kernel), ("env", env)):
        print(f"  {name:6s}: {wall:7.2f} s wall, {env_steps * args.num_envs / wall:9.0f} env steps/s "
              f"(world-steps), {1e6 * wall / physics_steps:7.1f} µs per physics step")
    print(f"  env over kernel: {100.0 * (env[0] / kernel[0] - 1.0):+.1f} % wall")
    same = all(r[3] == kernel[3] for side in runs for r in runs[side])
    print(f"  final state hashes {'agree' if same else 'DIFFER'}")
    if args.instructions:
        d1, d2 = (float(x) for x in args.instructions_durations.split(","))
        import ubersim
        dt = ubersim.VectorEnv(args.world, 1, controlled="none", frame_skip=args.frame_skip, robot=args.robot).dt
        per_step = {}
        for side in ("kernel", "env"):
            a, b = callgrind_total(args, side, d1), callgrind_total(args, side, d2)
            steps = (round(d2 / dt) - round(d1 / dt)) * args.num_envs
            per_step[side] = (b - a) / steps
            print(f"  {side:6s}: {per_step[side] / 1e6:8.2f} M instructions per env step (callgrind)")
        print(f"  env over kernel: {100.0 * (per_step['env'] / per_step['kernel'] - 1.0):+.1f} % instructions")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
