#!/usr/bin/env python3
"""The bits of 2/pi for the exact (Payne-Hanek) argument reduction of pendula's sine and cosine
(crates/pendula/src/num/trig/exact.rs), and the two-double split of pi/2 it multiplies by.

Run: python3 two_over_pi.py   (needs mpmath only for the cross-check)

2/pi is computed twice, independently: from Machin's formula pi = 16 atan(1/5) - 4 atan(1/239)
in exact integer arithmetic, and by mpmath; the script stops unless both give the same bits.
Prints the table as Rust: a word of zeros, then 19 words of 64 bits after the binary point,
most significant first (the first ones are also fdlibm's `ipio2` table in 24-bit pieces:
0xA2F983, 0x6E4E44, 0x1529FC, 0x2757D1, ...).
"""
import mpmath as mp

WORDS = 19
BITS = 64 * WORDS
GUARD = 64


def arctan_inv(n, one):
    """atan(1/n) * one, truncated, by its alternating series in integers."""
    total = term = one // n
    k, sign, n2 = 1, -1, n * n
    while term:
        term //= n2
        total += sign * (term // (2 * k + 1))
        sign, k = -sign, k + 1
    return total


one = 1 << (BITS + GUARD)
pi = 4 * (4 * arctan_inv(5, one) - arctan_inv(239, one))  # pi * 2^(BITS + GUARD), to a few units
machin = ((2 * one * one) // pi) >> GUARD  # floor(2/pi * 2^BITS), the guard absorbing those units

mp.mp.prec = BITS + 256
reference = int(mp.floor(2 / mp.pi * mp.mpf(2) ** BITS))
assert machin == reference, "Machin's formula and mpmath disagree"

print("const TWO_OVER_PI: [u64; %d] = [" % (WORDS + 1))
print("    0x0000_0000_0000_0000,")
for i in range(WORDS):
    w = (machin >> (BITS - 64 * (i + 1))) & (2**64 - 1)
    h = "%016X" % w
    print("    0x%s_%s_%s_%s," % (h[0:4], h[4:8], h[8:12], h[12:16]))
print("];")

half_pi = mp.pi / 2
hi = float(half_pi)
lo = float(half_pi - mp.mpf(hi))
print("PIO2_HI =", repr(hi), " PIO2_LO =", repr(lo), " error", mp.nstr(half_pi - hi - lo, 3))
