#!/usr/bin/env python3
"""Reference for cli.rs's rk4_integrates_a_huge_angle: the double pendulum started at
theta1 = 1e17 rad, classical RK4, h = 1e-3 s, 1000 steps.

Run: python3 huge_angle.py   (needs mpmath; prints the values the test embeds)

In double precision theta1 = 1e17 cannot move: an ulp there is 16 rad, and every increment
h*omega (and every stage's) is far below half of it, so theta1 and each stage's theta1 stay
1e17, and theta1 - theta2 rounds to 1e17 as well (|theta2| < 8 rad throughout). Every method
of pendula therefore integrates (theta2, omega1, omega2) with sin(theta1), sin(theta1 - theta2)
equal to sin(1e17) and cos(theta1 - theta2) equal to cos(1e17), held fixed. This script does
the same RK4 steps at 40 significant digits, with sin(1e17) and cos(1e17) by mpmath (which
reduces 1e17 exactly), and the equations in the textbook form M(theta) theta'' = -(C + G) of
tests/reference/mpmath_reference.py (not pendula's expression order): what is left between it
and pendula is rounding, about 1e-15, and any error in pendula's sin(1e17) or cos(1e17).
"""
import mpmath as mp

mp.mp.dps = 40

m1, m2, l1, l2, g = 1, 1, 1, 1, mp.mpf("9.81")
theta1 = mp.mpf(10) ** 17
theta2 = mp.mpf(-0.17453292519943295)  # -10 deg as pendula's double holds it (the default)
s1 = sd = mp.sin(theta1)
cd = mp.cos(theta1)


def rates(y):
    th2, w1, w2 = y
    a = (m1 + m2) * l1**2
    b = m2 * l1 * l2 * cd
    c = m2 * l2**2
    x1 = m2 * l1 * l2 * w2**2 * sd + g * l1 * (m1 + m2) * s1
    x2 = -m2 * l1 * l2 * w1**2 * sd + m2 * g * l2 * mp.sin(th2)
    det = a * c - b * b
    return [w2, -(c * x1 - b * x2) / det, -(-b * x1 + a * x2) / det]


h = mp.mpf("1e-3")
y = [theta2, mp.mpf(0), mp.mpf(0)]
for _ in range(1000):
    k1 = rates(y)
    k2 = rates([v + h / 2 * k for v, k in zip(y, k1)])
    k3 = rates([v + h / 2 * k for v, k in zip(y, k2)])
    k4 = rates([v + h * k for v, k in zip(y, k3)])
    y = [v + h / 6 * (a + 2 * b + 2 * c + d) for v, a, b, c, d in zip(y, k1, k2, k3, k4)]

# At rest the energy is the potential V = -(m1 + m2) g l1 cos(theta1) - m2 g l2 cos(theta2).
energy = -(m1 + m2) * g * l1 * mp.cos(theta1) - m2 * g * l2 * mp.cos(theta2)
print("sin(1e17) =", mp.nstr(s1, 20), " cos(1e17) =", mp.nstr(cd, 20))
print("initial energy (at rest) =", mp.nstr(energy, 20))
print("final theta2, omega1, omega2 =", ", ".join(mp.nstr(v, 20) for v in y))
