#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""How ubersim.dask scales: the same N seeded worlds on a LocalCluster of 1 worker process, then of
2 (or --workers), one thread each, on 127.0.0.1. Prints each run's wall time and the speed-up, and
checks that both runs gave the same state hashes (exit 1 if not, or if a world failed).

    PYTHONPATH=build/python /usr/bin/python3 tools/dask_scaling.py --worlds 16 --duration 120

Each cluster is started and warmed up (every worker loads the module and a world) before its
clock starts, so the figure is the tasks' scaling, not the cluster's start-up. A benchmark, not a
test: the machine's other load shows in the figure (it prints nproc and the load average; --repeat
takes the fastest of a few runs).
"""
import argparse
import os
import sys
import time


def warm_up():
    """Run in every worker before timing: load the package and one world."""
    import ubersim
    ubersim.World("div-b").step(1)
    return os.getpid()


def timed_run(workers, args):
    import distributed
    import ubersim.dask as ud

    with ud.local_cluster(workers) as cluster, distributed.Client(cluster) as client:
        client.wait_for_workers(workers)
        client.run(warm_up)
        walls = []
        for _ in range(args.repeat):
            start = time.perf_counter()
            results = ud.run_worlds(client, args.world, range(args.seed, args.seed + args.worlds), args.duration,
                                    play="random", profile="fast", progress=not args.quiet)
            walls.append(time.perf_counter() - start)
    return min(walls), results


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worlds", type=int, default=16, help="seeded worlds per run (default 16)")
    parser.add_argument("--duration", type=float, default=120.0, help="simulated s per world (default 120)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes of the second run (default 2)")
    parser.add_argument("--world", default="div-b", help="a shipped world's name or a world file (default div-b)")
    parser.add_argument("--seed", type=int, default=1, help="the first seed (default 1)")
    parser.add_argument("--repeat", type=int, default=1, help="runs per cluster, the fastest counts (default 1)")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    args = parser.parse_args()

    load = os.getloadavg()
    print(f"nproc {os.cpu_count()}, load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; "
          f"{args.worlds} worlds x {args.duration:g} s simulated ({args.world}, random play, fast profile)")
    one_wall, one = timed_run(1, args)
    print(f"1 worker:  {one_wall:.2f} s wall (in the workers: {sum(r.wall_time for r in one):.2f} s)")
    many_wall, many = timed_run(args.workers, args)
    print(f"{args.workers} workers: {many_wall:.2f} s wall "
          f"(tasks per worker: {sorted(_count(r.worker for r in many).values())})")
    print(f"speed-up {one_wall / many_wall:.2f}x on {args.workers} workers")

    failed = [r for r in one + many if not r.ok]
    for r in failed:
        print(f"seed {r.seed}: {r.error}", file=sys.stderr)
    mismatched = [(a.seed, a.state_hash, b.state_hash) for a, b in zip(one, many) if a.state_hash != b.state_hash]
    for seed, a, b in mismatched:
        print(f"seed {seed}: state hash {a} on 1 worker, {b} on {args.workers}", file=sys.stderr)
    if failed or mismatched:
        return 1
    print(f"the {args.worlds} state hashes agree")
    return 0


def _count(items):
    counts = {}
    for item in items:
        counts[item] = counts.get(item, 0) + 1
    return counts


if __name__ == "__main__":
    sys.exit(main())
