#!/usr/bin/env python3
"""Correctly rounded sine and cosine of hard arguments, for tests/trig.rs.

Run: python3 trig_hard_cases.py   (needs mpmath; prints the Rust table the test embeds)

Each x is a double; mpmath evaluates sin x and cos x with 1500 bits of working precision
(enough to reduce even f64::MAX, about 2^1024, with 400 bits to spare) and rounds them to the
nearest double. The arguments: huge values, the largest double, the double nearest a multiple
of pi/2 (6381956970095103 * 2^797; Muller, Elementary Functions, ch. 11), the doubles nearest
pi/2 and pi, the edge of the fast range (2^20), the smallest doubles, and their finite
neighbours.
"""
import math
import sys

import mpmath as mp

mp.mp.prec = 1500

named = [
    1e17,
    1e22,
    1e300,
    sys.float_info.max,
    6381956970095103 * 2.0**797,
    math.pi / 2,
    math.pi,
    2.0**20,
    2.0**-1022,
    5e-324,
]
xs = []
for x in named:
    xs += [y for y in (x, math.nextafter(x, math.inf), math.nextafter(x, 0.0)) if math.isfinite(y)]

print("const HARD: [(f64, f64, f64); %d] = [" % len(xs))
for x in xs:
    m = mp.mpf(x)
    assert m == x
    print("    (%r, %r, %r)," % (x, float(mp.sin(m)), float(mp.cos(m))))
print("];")
