"""pendula.distributed against the local call, side by side in one process (issue 15). Not a
test: run it by hand with the package built optimised (see bench.py) and `distributed`:

    python crates/pendula-py/bench/dask_fractal.py [--n 1024] [--t-max 100]

The flip fractal of an n × n grid to t-max s: `pendula.fractal` with 2 threads, against
`pendula.distributed.fractal` on a LocalCluster of 2 worker processes with 1 thread each
(processes on loopback), both on this machine; the ratio is the distributed run's overhead.
The results are compared byte for byte.
"""

from __future__ import annotations

import argparse
import math
import time

import pendula
import pendula.distributed


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--n", type=int, default=1024)
    p.add_argument("--t-max", type=float, default=100.0)
    p.add_argument("--runs", type=int, default=2)
    a = p.parse_args()
    from dask.distributed import Client, LocalCluster

    kw = dict(theta1=(-math.pi, math.pi, a.n), theta2=(-math.pi, math.pi, a.n), t_max=a.t_max)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None) as cluster, Client(cluster) as client:
        print(f"## Flip fractal {a.n}² to {a.t_max:g} s: pendula.distributed (2 worker processes) vs pendula.fractal (2 threads)\n")
        print("| run | local 2 threads | distributed, 2 workers | distributed/local | same bytes |")
        print("|---|---|---|---|---|")
        for r in range(a.runs):
            t = time.perf_counter()
            local = pendula.fractal(threads=2, **kw)
            tl = time.perf_counter() - t
            t = time.perf_counter()
            remote = pendula.distributed.fractal(client, threads=1, **kw)
            td = time.perf_counter() - t
            same = all(getattr(local, k).tobytes() == getattr(remote, k).tobytes() for k in ("flip_time", "flip_time_half_step", "converged"))
            print(f"| {r + 1} | {tl:.2f} s | {td:.2f} s | {td / tl:.3f} | {same} |")


if __name__ == "__main__":
    main()
