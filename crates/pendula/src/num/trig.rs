//! Sine and cosine for lanes of f64, written so that loops over lanes auto-vectorise (no
//! table lookups, no data-dependent branches) in the range pendulums live in, and correct for
//! every finite argument.
//!
//! **Fast path**, |x| ≤ [`FAST_RANGE`] = 2²⁰: x = k π/2 + r with k = round(2x/π) (round to
//! nearest even, by the 1.5·2⁵² trick) and r by a two-part Cody–Waite reduction (π/2 split
//! into fdlibm's 33-bit piece P₁, whose last two bits are zero, so k·P₁ is exact for
//! |k| < 2²², and the rest); then sin r and cos r by the minimax polynomials of fdlibm's
//! `__kernel_sin` and `__kernel_cos` on |r| ≤ π/4, and the quadrant k mod 4 selects and signs
//! them. [`sin`] alone reduces by π instead (one polynomial, no select).
//!
//! **Beyond**, and for infinities: the exact (Payne–Hanek) reduction of [`exact`], scalar,
//! which `sin_cos_with::<_, true>` (`WIDE`) takes for the arguments that are not [`is_fast`].
//! The lane kernels stay branch-free: their fast copy (`WIDE` false) only tracks how far each
//! lane's angles reach (or, in the driven kernel, a bound from its speeds), and a lane group
//! that may have gone beyond the fast range runs again with the `WIDE` copy, in which lanes in
//! the fast range get the same bits as before.
//!
//! Accuracy, against the platform's `sin`/`cos` (glibc) over every finite double (exponents
//! drawn uniformly, and values next to multiples of π/2) and against mpmath on hard cases
//! (tests/trig.rs): in the fast range within 2 ulp plus an absolute 6.8·10⁻²¹, the two-part
//! reduction's error |k|·3.5·10⁻²⁷ + ½ ulp(k·P2T), which shows only where the result is tiny,
//! next to a multiple of π/2 (measured: 5.7·10⁻²¹ at most over 10⁶ such values); beyond the
//! fast range within 1 ulp. NaN and ±∞ give NaN.
//!
//! # References
//! - W. J. Cody, W. Waite, *Software Manual for the Elementary Functions*, 1980 (reduction).
//! - fdlibm 5.3 (Sun Microsystems, 1993), `k_sin.c`, `k_cos.c`, `e_rem_pio2.c` (coefficients
//!   and the split of π/2).
//! - M. H. Payne, R. N. Hanek, *Radian reduction for trigonometric functions*, 1983, and
//!   J.-M. Muller, *Elementary Functions*, 3rd ed., 2016, ch. 11 (the exact reduction; see
//!   [`exact`]).

pub mod exact;

/// The largest |x| the fast path serves: 2²⁰ rad (about 1.7·10⁵ turns), where k ≤ 667 544
/// keeps k·P₁ exact with room to spare and the reduction's absolute error below 6.8·10⁻²¹.
pub const FAST_RANGE: f64 = 1_048_576.0;

/// Whether the fast path serves x: |x| ≤ [`FAST_RANGE`], or x is NaN, which both paths turn
/// into NaN.
#[inline(always)]
pub fn is_fast(x: f64) -> bool {
    (x.abs() <= FAST_RANGE) | x.is_nan()
}

/// 2/π.
const TWO_OVER_PI: f64 = std::f64::consts::FRAC_2_PI;
/// π/2 ≈ P1 + P2T: P1 is fdlibm's `pio2_1`, the first 33 bits of π/2, of which the last two
/// are zero (so k·P1 is exact for |k| < 2²², |x| < 6.6·10⁶), P2T is the
/// double nearest π/2 − P1 (fdlibm's `pio2_1t`, 3.5·10⁻²⁷ from it by mpmath); the reduction's
/// absolute error is then at most |k|·3.5·10⁻²⁷ + ½ ulp(k·P2T), far below an ulp of r except
/// near the multiples of π/2, where r itself is tiny.
const P1: f64 = 1.570_796_326_734_125_6;
const P2T: f64 = 6.077_100_506_506_192e-11;
/// 1.5·2⁵²: adding and subtracting it rounds to the nearest integer (ties to even).
const ROUND: f64 = 6_755_399_441_055_744.0;

const S1: f64 = -1.666_666_666_666_663_2e-1;
const S2: f64 = 8.333_333_333_322_49e-3;
const S3: f64 = -1.984_126_982_985_795e-4;
const S4: f64 = 2.755_731_370_707_007e-6;
const S5: f64 = -2.505_076_025_340_686_3e-8;
const S6: f64 = 1.589_690_995_211_55e-10;

#[allow(clippy::excessive_precision)] // fdlibm's digits
const C1: f64 = 4.166_666_666_666_660_2e-2;
const C2: f64 = -1.388_888_888_887_411e-3;
const C3: f64 = 2.480_158_728_947_673e-5;
const C4: f64 = -2.755_731_435_139_066_3e-7;
const C5: f64 = 2.087_572_321_298_175e-9;
const C6: f64 = -1.135_964_755_778_819_5e-11;

/// a·b + c: fused (one rounding) when `FMA`, else a product and a sum. Only kernels that
/// run where the CPU has FMA instructions use `FMA = true`; elsewhere `mul_add` would be a
/// slow software routine.
#[inline(always)]
pub fn madd<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FMA { a.mul_add(b, c) } else { a * b + c }
}

/// sin x and cos x for every x (see the module documentation for the method and accuracy):
/// the fast path where [`is_fast`], else the exact reduction.
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    sin_cos_with::<false, true>(x)
}

/// [`sin_cos`], with fused multiply-adds in the polynomials when `FMA`; when not `WIDE`, the
/// fast path alone, branch-free, for arguments that are [`is_fast`] (beyond, its result is
/// wrong).
#[inline(always)]
pub fn sin_cos_with<const FMA: bool, const WIDE: bool>(x: f64) -> (f64, f64) {
    if WIDE && !is_fast(x) {
        return exact::sin_cos(x);
    }
    let shifted = x * TWO_OVER_PI + ROUND;
    let k = shifted - ROUND;
    // The low bits of the shifted value are k's: its quadrant.
    let quadrant = shifted.to_bits() & 3;
    let r = (x - k * P1) - k * P2T;
    let z = r * r;
    let (s, c) = (kernel_sin::<FMA>(r, z), kernel_cos::<FMA>(z));
    // Quadrant q: sin = (s, c, −s, −c)[q], cos = (c, −s, −c, s)[q].
    let odd = quadrant & 1 == 1;
    let (sin_abs, cos_abs) = if odd { (c, s) } else { (s, c) };
    let sin_sign = (quadrant & 2) << 62;
    let cos_sign = ((quadrant + 1) & 2) << 62;
    (f64::from_bits(sin_abs.to_bits() ^ sin_sign), f64::from_bits(cos_abs.to_bits() ^ cos_sign))
}

/// fdlibm's `__kernel_sin` on |r| ≤ π/4 (z = r²).
#[inline(always)]
fn kernel_sin<const FMA: bool>(r: f64, z: f64) -> f64 {
    let m = madd::<FMA>;
    let tail = m(z, m(z, m(z, m(z, S6, S5), S4), S3), S2);
    m(z * r, m(z, tail, S1), r)
}

/// fdlibm's `__kernel_cos` on |r| ≤ π/4 (z = r²).
#[inline(always)]
fn kernel_cos<const FMA: bool>(z: f64) -> f64 {
    let m = madd::<FMA>;
    let poly = z * m(z, m(z, m(z, m(z, m(z, C6, C5), C4), C3), C2), C1);
    let half = 0.5 * z;
    let w = 1.0 - half;
    w + m(z, poly, (1.0 - w) - half)
}

/// 1/π.
const ONE_OVER_PI: f64 = std::f64::consts::FRAC_1_PI;

/// sin r = r + r³ P(r²) on |r| ≤ π/2, P of degree 7 fitted by mpmath's Chebyshev
/// approximation (`tests/reference/sine_coefficients.py`; its error, 3.4e-19, is far below an
/// ulp), lowest degree first: two terms fewer than the Taylor series to the same accuracy.
#[allow(clippy::excessive_precision)] // the digits mpmath printed
const SIN_POLY: [f64; 8] = [
    -0.16666666666666666633,
    0.0083333333333333158688,
    -0.00019841269841254973769,
    2.7557319219163233416e-6,
    -2.5052107616996182891e-8,
    1.6058977312464087621e-10,
    -7.6439702967985720524e-13,
    2.7314447669863993424e-15,
];

/// sin x alone, branch-free and cheaper than [`sin_cos`]: x = qπ + r with |r| ≤ π/2 (the same
/// two-part reduction with 2P₁, 2P2T), sin x = (−1)^q sin r, and sin r by the
/// polynomial `SIN_POLY` (degree 7 in r²) — one polynomial and no select. Beyond the fast
/// range, the exact reduction.
#[inline(always)]
pub fn sin(x: f64) -> f64 {
    sin_with::<false, true>(x)
}

/// [`sin`], with fused multiply-adds in the polynomial when `FMA`; when not `WIDE`, the fast
/// path alone, as for [`sin_cos_with`].
#[inline(always)]
pub fn sin_with<const FMA: bool, const WIDE: bool>(x: f64) -> f64 {
    if WIDE && !is_fast(x) {
        return exact::sin_cos(x).0;
    }
    let shifted = x * ONE_OVER_PI + ROUND;
    let q = shifted - ROUND;
    let sign = (shifted.to_bits() & 1) << 63;
    let r = (x - q * (2.0 * P1)) - q * (2.0 * P2T);
    let z = r * r;
    // r + r³ P(r²): the leading term added last, for accuracy.
    let mut acc = SIN_POLY[7];
    for &c in SIN_POLY[..7].iter().rev() {
        acc = madd::<FMA>(z, acc, c);
    }
    f64::from_bits(madd::<FMA>(r * z, acc, r).to_bits() ^ sign)
}
