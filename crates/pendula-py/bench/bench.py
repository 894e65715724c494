"""Benchmarks of the Python package, side by side in one process, reported as ratios
(issue 14). Not a test: run it by hand, with the package built optimised:

    VIRTUAL_ENV=$PWD/target/py-venv target/py-venv/bin/maturin develop --release -m crates/pendula-py/Cargo.toml
    target/py-venv/bin/python crates/pendula-py/bench/bench.py [--quick]

It measures, on the benchmark specification's double pendulum (../shared/bench/SPEC.md):

- W2: `pendula.solve(..., method="dop853", rtol=atol=1e-10)` against scipy's
  `solve_ivp(method="DOP853")` at the same tolerances on the same right-hand side (the
  specification's canonical expression, in plain Python as scipy users write it), and
  heyoka.py's `taylor_adaptive` (build/JIT and propagation separately) when it is installed,
  also at matching accuracy: both over a ladder of tolerances, compared at equal errors;
- the per-call overhead of `pendula.solve` on a 10-step run;
- W3: `pendula.ensemble` on the 256 × 256 grid against `pendula sweep` (the release CLI)
  computing the same bytes.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import pendula

ROOT = Path(__file__).resolve().parents[3]
Y0 = [120 * math.pi / 180, -10 * math.pi / 180, 0.0, 0.0]
W2_REF = np.array([-0.80261199633036104544, -2.4815018039172568802, -1.9522456761809047925, -2.3287508056909700408])


def timed(f, runs):
    times = []
    out = None
    for _ in range(runs):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def rhs(t, y):
    # The specification's canonical evaluation order, m1 = m2 = l1 = l2 = 1, g = 9.81.
    th1, th2, w1, w2 = y
    d = th1 - th2
    sd, cd = math.sin(d), math.cos(d)
    s1, s2 = math.sin(th1), math.sin(th2)
    m11, m12, m21, m22 = 2.0, cd, cd, 1.0
    r1 = -w2 * w2 * sd - 2.0 * 9.81 * s1
    r2 = w1 * w1 * sd - 9.81 * s2
    det = m11 * m22 - m12 * m21
    return [w1, w2, (r1 * m22 - m12 * r2) / det, (m11 * r2 - m21 * r1) / det]


def w2(runs):
    from scipy.integrate import solve_ivp

    print("## W2: DOP853-class, rtol = atol = 1e-10, t = 0 … 10 s\n")
    print("| program | median time | RHS evaluations | max abs error at 10 s | pendula/peer |")
    print("|---|---|---|---|---|")
    tp, sol = timed(lambda: pendula.solve("double", (0, 10), method="dop853", rtol=1e-10, atol=1e-10), runs)
    err = np.max(np.abs(sol.y[:, -1] - W2_REF))
    print(f"| pendula.solve | {tp * 1e3:.3f} ms | {sol.nfev} | {err:.1e} | — |")
    ts, ref = timed(lambda: solve_ivp(rhs, (0, 10), Y0, method="DOP853", rtol=1e-10, atol=1e-10), max(3, runs // 10))
    err = np.max(np.abs(ref.y[:, -1] - W2_REF))
    print(f"| scipy solve_ivp DOP853 | {ts * 1e3:.1f} ms | {ref.nfev} | {err:.1e} | {tp / ts:.4f} ({ts / tp:.0f}× faster) |")
    try:
        import heyoka as hy
    except ImportError:
        print("| heyoka.py taylor_adaptive | not installed | | | |")
        return
    th1, th2, w1, w2_ = hy.make_vars("th1", "th2", "w1", "w2")
    d = th1 - th2
    m12 = hy.cos(d)
    r1 = -w2_ * w2_ * hy.sin(d) - 2.0 * 9.81 * hy.sin(th1)
    r2 = w1 * w1 * hy.sin(d) - 9.81 * hy.sin(th2)
    det = 2.0 - m12 * m12
    sys_ = [(th1, w1), (th2, w2_), (w1, (r1 - m12 * r2) / det), (w2_, (2.0 * r2 - m12 * r1) / det)]
    # The first build compiles with LLVM; later identical builds hit heyoka's cache.
    tb, ta = timed(lambda: hy.taylor_adaptive(sys_, Y0, tol=1e-10), 1)

    def propagate(ta):
        ta.time = 0.0
        ta.state[:] = Y0
        ta.propagate_until(10.0)
        return ta.state.copy()

    tprop, state = timed(lambda: propagate(ta), runs)
    err = np.max(np.abs(state - W2_REF))
    print(f"| heyoka.py taylor_adaptive (tol 1e-10) | build/JIT (first, in this process) {tb * 1e3:.0f} ms, propagation {tprop * 1e3:.3f} ms | - | {err:.1e} | {tp / tprop:.2f} (propagation) |")

    # At matching accuracy: each program's time against its error at 10 s over a ladder of
    # tolerances, and the two curves compared at the same errors (log-log interpolation).
    def curve(points):
        points = sorted(points)  # by error
        return np.log10([e for e, _ in points]), np.log10([t for _, t in points])

    ours, theirs = [], []
    print("\n| tolerance | pendula dop853: error, time | heyoka: error, propagation, build |")
    print("|---|---|---|")
    for tol in (1e-6, 1e-8, 1e-10, 1e-12, 1e-14):
        t1, sol = timed(lambda: pendula.solve("double", (0, 10), method="dop853", rtol=tol, atol=tol), runs)
        e1 = np.max(np.abs(sol.y[:, -1] - W2_REF))
        tb, ta = timed(lambda: hy.taylor_adaptive(sys_, Y0, tol=tol), 1)
        t2, state = timed(lambda: propagate(ta), runs)
        e2 = np.max(np.abs(state - W2_REF))
        ours.append((e1, t1))
        theirs.append((e2, t2))
        print(f"| {tol:.0e} | {e1:.1e}, {t1 * 1e3:.3f} ms | {e2:.1e}, {t2 * 1e3:.3f} ms, {tb * 1e3:.0f} ms |")
    (ex, et), (hx, ht) = curve(ours), curve(theirs)
    print("\n| error at 10 s | pendula dop853 | heyoka propagation | pendula/heyoka |")
    print("|---|---|---|---|")
    for target in (1e-6, 1e-8, 1e-10, 1e-12):
        lt = math.log10(target)
        if ex[0] <= lt <= ex[-1] and hx[0] <= lt <= hx[-1]:
            a, b = 10 ** np.interp(lt, ex, et), 10 ** np.interp(lt, hx, ht)
            print(f"| {target:.0e} | {a * 1e3:.3f} ms | {b * 1e3:.3f} ms | {a / b:.2f} |")
        else:
            print(f"| {target:.0e} | outside one program's range | | |")


def overhead(runs):
    print("\n## Per-call overhead: pendula.solve, rk4, 10 steps\n")
    system = pendula.System("double")
    t, _ = timed(lambda: pendula.solve(system, (0, 0.01), method="rk4", dt=1e-3), runs)
    t0, _ = timed(lambda: None, runs)
    print(f"median {(t - t0) * 1e6:.1f} µs per call (10 steps, 11 samples recorded)")


def w3(runs, threads):
    print("\n## W3: 256 × 256 grid, RK4 h = 1e-2, 1000 steps\n")
    n = 256
    c = np.array([-math.pi + (i + 0.5) * (2 * math.pi) / n for i in range(n)])
    g1, g2 = np.meshgrid(c, c)
    y0s = np.stack([g1.ravel(), g2.ravel(), np.zeros(n * n), np.zeros(n * n)], axis=1)
    tp, r = timed(lambda: pendula.ensemble("double", y0s, method="rk4", dt=1e-2, steps=1000, threads=threads,
                                                record=("final", "flip-time")), runs)
    cli = str(Path(os.environ.get("PENDULA", ROOT / "target" / "release" / "pendula")).resolve())
    with tempfile.TemporaryDirectory() as tmp:
        args = [cli, "sweep", "double", "--grid", "theta1=-pi:pi:256", "--grid", "theta2=-pi:pi:256", "--dt", "1e-2",
                "--steps", "1000", "--record", "final,flip-time", "--out", "w3.npy", "--threads", str(threads)]
        tc, _ = timed(lambda: subprocess.run(args, cwd=tmp, check=True, capture_output=True), runs)
        same = np.load(Path(tmp) / "w3.npy").tobytes() == r.data.tobytes()
    print("| program | threads | median wall | pendula.ensemble/peer |")
    print("|---|---|---|---|")
    print(f"| pendula.ensemble | {threads} | {tp:.3f} s | — |")
    print(f"| pendula sweep (CLI, whole process) | {threads} | {tc:.3f} s | {tp / tc:.3f} |")
    print(f"\nsame bytes: {same}")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--quick", action="store_true", help="fewer repetitions")
    p.add_argument("--threads", type=int, default=os.cpu_count())
    a = p.parse_args()
    runs = 5 if a.quick else 20
    print(f"pendula {pendula.__version__}, Python {sys.version.split()[0]}, numpy {np.__version__}\n")
    w2(runs * 5)
    overhead(runs * 50)
    w3(max(3, runs // 4), a.threads)


if __name__ == "__main__":
    main()
