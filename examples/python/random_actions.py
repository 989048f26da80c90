#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Random actions in 64 worlds: trains nothing, prints env steps per second (docs/python.md).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/random_actions.py [--world div-a] [--num-envs 64]
"""
import argparse
import time

import numpy as np

import ubersim
from ubersim import tasks

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("--world", default="div-b")
parser.add_argument("--num-envs", type=int, default=64)
parser.add_argument("--steps", type=int, default=400, help="env steps (each frame_skip physics steps)")
parser.add_argument("--seed", type=int, default=0)
args = parser.parse_args()

env = ubersim.VectorEnv(args.world, args.num_envs, task=tasks.GoToBall(), opponent="scripted", seed=args.seed)
obs, info = env.reset(seed=args.seed)
rng = np.random.default_rng(args.seed)
low, high = env.action_space.low, env.action_space.high
episodes = 0
start = time.perf_counter()
for _ in range(args.steps):
    obs, reward, terminated, truncated, info = env.step(rng.uniform(low, high).astype(np.float32))
    episodes += int(np.count_nonzero(terminated | truncated))
wall = time.perf_counter() - start
env_steps = args.steps * env.num_envs
print(f"{args.world}: {env.num_envs} worlds, {env_steps} env steps ({env.dt * 1000:.0f} ms each, profile "
      f"{env.worlds.profile}) in {wall:.2f} s: {env_steps / wall:.0f} env steps/s, "
      f"{env_steps * env.dt / wall:.0f}× real time summed over the worlds; {episodes} episodes ended")
