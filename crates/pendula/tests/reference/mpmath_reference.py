#!/usr/bin/env python3
"""Independent high-precision reference values for pendula's tests.

Run: python3 mpmath_reference.py   (needs mpmath; prints the values the tests embed)

Nothing here shares code with pendula: the ODEs are integrated by mpmath's Taylor-series
method (mpmath.odefun) at 30 significant digits, and the special functions are mpmath's.
"""
import mpmath as mp

mp.mp.dps = 30


def double_pendulum(m1, m2, l1, l2, g):
    """Lagrangian equations of motion, solved from M(theta) theta'' = -(C + G) directly."""

    def f(t, y):
        th1, th2, w1, w2 = y
        d = th1 - th2
        a = (m1 + m2) * l1**2
        b = m2 * l1 * l2 * mp.cos(d)
        c = m2 * l2**2
        x1 = m2 * l1 * l2 * w2**2 * mp.sin(d) + g * l1 * (m1 + m2) * mp.sin(th1)
        x2 = -m2 * l1 * l2 * w1**2 * mp.sin(d) + m2 * g * l2 * mp.sin(th2)
        det = a * c - b * b
        return [w1, w2, -(c * x1 - b * x2) / det, -(-b * x1 + a * x2) / det]

    return f


def show(name, values):
    print(f"{name}: [" + ", ".join(mp.nstr(v, 20) for v in values) + "]")


deg = mp.pi / 180
cases = {
    "DOUBLE_A (m=1,1 l=1,1 g=9.81; 120deg,-10deg,0,0; t=2)": (
        (1, 1, 1, 1, mp.mpf("9.81")), [120 * deg, -10 * deg, 0, 0], 2),
    "DOUBLE_B (m=1,2 l=1,0.5 g=9.81; 60deg,90deg,0.5,-1; t=2)": (
        (1, 2, 1, mp.mpf("0.5"), mp.mpf("9.81")), [60 * deg, 90 * deg, mp.mpf("0.5"), -1], 2),
    "DOUBLE_C (m=1,1 l=1,1 g=9.81; 30deg,-20deg,0.3,0; t=2)": (
        (1, 1, 1, 1, mp.mpf("9.81")), [30 * deg, -20 * deg, mp.mpf("0.3"), 0], 2),
}
# The bench's W2 problem at t = 10 s (takes about 5 minutes).
cases["DOUBLE_W2 (m=1,1 l=1,1 g=9.81; 120deg,-10deg,0,0; t=10)"] = (
    (1, 1, 1, 1, mp.mpf("9.81")), [120 * deg, -10 * deg, 0, 0], 10)
for name, (params, y0, t) in cases.items():
    sol = mp.odefun(double_pendulum(*params), 0, y0)
    show(name, sol(t))

# Simple pendulum theta'' = -(g/l) sin theta, l = 1, g = 9.81.
pend = lambda t, y: [y[1], -mp.mpf("9.81") * mp.sin(y[0])]
for th0, w0, t in [(60, 0, mp.mpf("1.3")), (170, 0, mp.mpf("2.5")), (30, -2, mp.mpf("0.7")), (10, 7, mp.mpf("1.1"))]:
    sol = mp.odefun(pend, 0, [th0 * deg, w0])
    show(f"PENDULUM theta0={th0}deg omega0={w0} t={t}", sol(t))

for k in ["0", "0.5", "0.9", "0.999"]:
    print(f"K({k}) =", mp.nstr(mp.ellipk(mp.mpf(k) ** 2), 20))
for phi, k in [("0.7", "0.5"), ("2.5", "0.8"), ("-4.0", "0.3")]:
    print(f"F({phi}, {k}) =", mp.nstr(mp.ellipf(mp.mpf(phi), mp.mpf(k) ** 2), 20))
for u, k in [("0.6", "0.5"), ("3.7", "0.95"), ("-2.2", "0.2")]:
    m = mp.mpf(k) ** 2
    vals = [mp.ellipfun(n, mp.mpf(u), m=m) for n in ("sn", "cn", "dn")]
    show(f"sn,cn,dn({u}, {k})", vals)
print("period 170deg, l=1, g=9.81 =", mp.nstr(4 * mp.sqrt(1 / mp.mpf("9.81")) * mp.ellipk(mp.sin(85 * deg) ** 2), 20))
