//! Sine and cosine of every finite double by an exact (Payne–Hanek) argument reduction: the
//! path of [`super`]'s functions beyond [`super::FAST_RANGE`], where the lanes' two-part
//! Cody–Waite reduction no longer holds. Scalar and branchy; a pendulum reaches it only when
//! an angle is set or grows beyond 2²⁰ rad.
//!
//! x = m·2ᵉ with m < 2⁵³ an integer, and x·2/π mod 4 (the quadrant and the fraction of the
//! next quarter turn) is m times the bits of 2/π = Σ bᵢ 2⁻ⁱ from i = e − 1 on: the bits before
//! contribute multiples of 4, and of those after, a 192-bit window suffices, since the rest
//! adds less than m·2⁻¹⁹⁰ < 2⁻¹³⁷ of a quarter turn. The product, in integer arithmetic,
//! gives the quadrant and the fraction f to 128 bits; rounded to the nearest quadrant,
//! |f| ≤ 1/2, and r = f·π/2 in double-double (|r| ≤ π/4). No double is closer to a multiple
//! of π/2 than 4.7·10⁻¹⁹ ≈ 2⁻⁶⁰·⁹ (x = 6381956970095103·2⁷⁹⁷, the worst case in Muller,
//! ch. 11; its r checked with mpmath), i.e. |f| > 2⁻⁶¹·⁵, so the 2⁻¹²⁸ to which f is known
//! leaves r at least 66 correct bits: fdlibm's `__kernel_sin` and `__kernel_cos`, given r
//! and its tail, then return sin r and cos r within 1 ulp.
//!
//! Measured against the platform's `sin`/`cos` (glibc) over the whole finite range, with
//! values next to multiples of π/2: within 1 ulp (tests/trig.rs).
//!
//! # References
//! - M. H. Payne, R. N. Hanek, *Radian reduction for trigonometric functions*, SIGNUM
//!   Newsletter 18(1), 1983, pp. 19–24 (the reduction by a window of 2/π).
//! - J.-M. Muller, *Elementary Functions: Algorithms and Implementation*, 3rd ed., Birkhäuser,
//!   2016, ch. 11 (Payne–Hanek in integer arithmetic; the worst cases of the reduction).
//! - fdlibm 5.3 (Sun Microsystems, 1993), `k_rem_pio2.c` (the same reduction in floating
//!   point; its `ipio2` table holds the bits below), `k_sin.c` and `k_cos.c` (the kernels with
//!   a tail), `k_cos.c` as revised in FreeBSD's msun (the w = 1 − z/2 split).

use super::{C1, C2, C3, C4, C5, C6, S1, S2, S3, S4, S5, S6};

/// The bits of 2/π after the binary point, 64 to a word, most significant first, after a word
/// of zeros that serves the smallest exponents (the window starts at word ⌊(e + 62)/64⌋, e ≥
/// −53 for |x| ≥ π/4, and the largest e = 971 needs words 16 to 19). Printed by
/// `tests/reference/two_over_pi.py`, which computes them by Machin's formula in integer
/// arithmetic and checks them against mpmath.
const TWO_OVER_PI: [u64; 20] = [
    0x0000_0000_0000_0000,
    0xA2F9_836E_4E44_1529,
    0xFC27_57D1_F534_DDC0,
    0xDB62_9599_3C43_9041,
    0xFE51_63AB_DEBB_C561,
    0xB724_6E3A_424D_D2E0,
    0x0649_2EEA_09D1_921C,
    0xFE1D_EB1C_B129_A73E,
    0xE882_35F5_2EBB_4484,
    0xE99C_7026_B45F_7E41,
    0x3991_D639_8353_39F4,
    0x9C84_5F8B_BDF9_283B,
    0x1FF8_97FF_DE05_980F,
    0xEF2F_118B_5A0A_6D1F,
    0x6D36_7ECF_27CB_09B7,
    0x4F46_3F66_9E5F_EA2D,
    0x7527_BAC7_EBE5_F17B,
    0x3D07_39F7_8A52_92EA,
    0x6BFB_5FB1_1F8D_5D08,
    0x5603_3046_FC7B_6BAB,
];

/// π/2 ≈ PIO2_HI + PIO2_LO to 1.5·10⁻³³ (the double nearest π/2 and the double nearest the
/// rest; `tests/reference/two_over_pi.py`).
const PIO2_HI: f64 = std::f64::consts::FRAC_PI_2;
const PIO2_LO: f64 = 6.123_233_995_736_766e-17;

/// 2ᵏ for −1022 ≤ k ≤ 1023, exactly.
fn pow2(k: i32) -> f64 {
    f64::from_bits(((1023 + k) as u64) << 52)
}

/// (q mod 4, r, r_tail) with x = q·π/2 + r + r_tail, |r| ≤ π/4, for finite x ≥ π/4;
/// r + r_tail carries at least 66 correct bits (see the module documentation).
fn reduce(x: f64) -> (u64, f64, f64) {
    let bits = x.to_bits();
    let e = ((bits >> 52) & 0x7ff) as i64 - 1075;
    let m = (bits & ((1 << 52) - 1)) | (1 << 52);
    // The window's first bit, i = e − 1, is at position i + 63 of the padded table.
    let start = (e + 62) as usize;
    let (w, s) = (start / 64, start % 64);
    let word = |k: usize| TWO_OVER_PI[w + k];
    let window: [u64; 3] =
        std::array::from_fn(|k| if s == 0 { word(k) } else { (word(k) << s) | (word(k + 1) >> (64 - s)) });
    // m·window = p₀·2¹²⁸ + p₁·2⁶⁴ + p₂, of which only bits 0 … 191 matter (x·2/π mod 4 is
    // the product times 2⁻¹⁹⁰ mod 4).
    let [p0, p1, p2] = window.map(|f| m as u128 * f as u128);
    let w0 = p2 as u64;
    let carry = (p2 >> 64) + (p1 as u64) as u128;
    let w1 = carry as u64;
    let w2 = ((carry >> 64) + (p1 >> 64) + (p0 as u64) as u128) as u64;
    let quadrant = w2 >> 62;
    // The fraction's 128 leading bits: bits 62 … 189 of the product.
    let fraction = (((w2 & ((1 << 62) - 1)) as u128) << 66) | ((w1 as u128) << 2) | (w0 >> 62) as u128;
    // From half a quarter turn on, the next multiple of π/2 is the nearer: f = fraction − 1.
    let up = fraction >> 127 == 1;
    let magnitude = if up { fraction.wrapping_neg() } else { fraction };
    if magnitude == 0 {
        return ((quadrant + up as u64) & 3, 0.0, 0.0);
    }
    // |f| = magnitude·2⁻¹²⁸ as a double-double: its leading 53 bits and the next 64.
    let shift = magnitude.leading_zeros() as i32;
    let n = magnitude << shift;
    let f_hi = (n >> 75) as u64 as f64 * pow2(-53 - shift);
    let f_lo = (n >> 11) as u64 as f64 * pow2(-117 - shift);
    // r = f·π/2: the product of the leading parts exactly (fused), the rest to 2⁻¹⁰⁶.
    let r = f_hi * PIO2_HI;
    let r_err = f_hi.mul_add(PIO2_HI, -r) + (f_hi * PIO2_LO + f_lo * PIO2_HI);
    let (r, r_tail) = two_sum_fast(r, r_err);
    let sign = if up { -1.0 } else { 1.0 };
    ((quadrant + up as u64) & 3, sign * r, sign * r_tail)
}

/// (a + b, its rounding error) for |a| ≥ |b| (Dekker's Fast2Sum).
fn two_sum_fast(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    (s, b - (s - a))
}

/// fdlibm's `__kernel_sin(r, tail, 1)`: sin(r + tail) on |r| ≤ π/4, |tail| ≤ ulp(r).
fn kernel_sin(r: f64, tail: f64) -> f64 {
    let z = r * r;
    let v = z * r;
    let p = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
    r - ((z * (0.5 * tail - v * p) - tail) - v * S1)
}

/// fdlibm's `__kernel_cos(r, tail)` (FreeBSD's form): cos(r + tail) on |r| ≤ π/4.
fn kernel_cos(r: f64, tail: f64) -> f64 {
    let z = r * r;
    let p = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    let half = 0.5 * z;
    let w = 1.0 - half;
    w + (((1.0 - w) - half) + (z * p - r * tail))
}

/// sin x and cos x for every finite x, within 1 ulp; NaN for infinite or NaN x.
#[cold]
#[inline(never)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    if !x.is_finite() {
        return (f64::NAN, f64::NAN);
    }
    let a = x.abs();
    let (quadrant, r, tail) = if a < std::f64::consts::FRAC_PI_4 { (0, a, 0.0) } else { reduce(a) };
    let (s, c) = (kernel_sin(r, tail), kernel_cos(r, tail));
    // sin and cos of |x| by quadrant, then sin(−|x|) = −sin |x|.
    let (sin, cos) = match quadrant {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    };
    (if x.is_sign_negative() { -sin } else { sin }, cos)
}
