//! The ensemble engine's sine and cosine (`ensemble::trig`) against the platform's (`f64::sin`
//! and `f64::cos`: glibc on Linux, whose reduction is exact) on the pendulum's range and over
//! every finite double — exponents drawn uniformly, values next to multiples of π/2, the edge
//! of the fast range — and against mpmath on named hard cases.

use pendula::ensemble::trig;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

use crate::support::samples;

/// Distance in units in the last place between two finite doubles.
fn ulps(a: f64, b: f64) -> u64 {
    let key = |x: f64| {
        let bits = x.to_bits() as i64;
        if bits < 0 { i64::MIN - bits } else { bits }
    };
    key(a).abs_diff(key(b))
}

/// The spacing of doubles just above |b|.
fn ulp(b: f64) -> f64 {
    let a = b.abs();
    f64::from_bits(a.to_bits() + 1) - a
}

/// The absolute error the fast path's two-part reduction may leave near the multiples of π/2
/// (|k|·3.5e-27 + ½ ulp(k·P₂) for |k| ≤ 2²⁰·2/π; see `trig`'s module documentation), where
/// the result itself is tiny.
const FAST_ABSOLUTE: f64 = 6.8e-21;

#[test]
fn ref_sine_and_cosine_are_within_two_ulps_of_the_platform() {
    let mut worst = (0u64, 0u64);
    for (lo, hi) in [(-1e4, 1e4), (-10.0, 10.0), (-1e-3, 1e-3), (-4.0, 4.0)] {
        for x in samples(200_000, lo, hi) {
            let (s, c) = trig::sin_cos(x);
            worst.0 = worst.0.max(ulps(s, x.sin())).max(ulps(trig::sin(x), x.sin()));
            worst.1 = worst.1.max(ulps(c, x.cos()));
        }
    }
    assert_eq!(trig::sin_cos(0.0), (0.0, 1.0));
    eprintln!("max ulps: sin {}, cos {}", worst.0, worst.1);
    assert!(worst.0 <= 2 && worst.1 <= 2, "{worst:?}");
}

/// Checks every variant at x against the platform: within 2 ulp, plus [`FAST_ABSOLUTE`] in the
/// fast range; the exact reduction alone within 1 ulp everywhere; and in the fast range the
/// kernels' two copies (fast alone, and for every angle) bit for bit the same.
fn check(x: f64) -> Result<(), TestCaseError> {
    let (sin, cos) = (x.sin(), x.cos());
    let allowance = if trig::is_fast(x) { FAST_ABSOLUTE } else { 0.0 };
    let within =
        |got: f64, want: f64| ulps(got, want) <= 2 || (got - want).abs() <= 2.0 * ulp(want) + allowance;
    let plain = trig::sin_cos(x);
    let fused = trig::sin_cos_with::<true, true>(x);
    for (name, got, want) in [
        ("sin_cos sin", plain.0, sin),
        ("sin_cos cos", plain.1, cos),
        ("fused sin_cos sin", fused.0, sin),
        ("fused sin_cos cos", fused.1, cos),
        ("sin", trig::sin(x), sin),
        ("fused sin", trig::sin_with::<true, true>(x), sin),
    ] {
        prop_assert!(
            within(got, want),
            "{name}({x:e}) = {got:e}, platform {want:e}: {} ulp",
            ulps(got, want)
        );
    }
    let exact = trig::exact::sin_cos(x);
    prop_assert!(
        ulps(exact.0, sin) <= 1 && ulps(exact.1, cos) <= 1,
        "exact::sin_cos({x:e}) = {exact:?}, platform ({sin:e}, {cos:e})"
    );
    if trig::is_fast(x) {
        let fast = trig::sin_cos_with::<false, false>(x);
        prop_assert_eq!(plain.0.to_bits(), fast.0.to_bits());
        prop_assert_eq!(plain.1.to_bits(), fast.1.to_bits());
        prop_assert_eq!(trig::sin(x).to_bits(), trig::sin_with::<false, false>(x).to_bits());
    }
    Ok(())
}

/// Any finite double, its biased exponent drawn uniformly from 0 (subnormals) to 2046.
fn any_finite() -> impl Strategy<Value = f64> {
    (any::<bool>(), 0u64..2047, any::<u64>()).prop_map(|(negative, exponent, bits)| {
        f64::from_bits(((negative as u64) << 63) | (exponent << 52) | (bits & ((1 << 52) - 1)))
    })
}

/// Doubles within a few ulp of k·π/2, |k| < 2⁴⁰ with log₂|k| drawn uniformly: where sin or
/// cos is tiny and a reduction's absolute error shows.
fn near_multiples_of_half_pi() -> impl Strategy<Value = f64> {
    (any::<bool>(), 0u32..40, any::<u64>(), -3i64..=3).prop_map(|(negative, bits, random, step)| {
        let k = (random >> (64 - bits - 1)) | 1;
        let x = k as f64 * std::f64::consts::FRAC_PI_2;
        let x = f64::from_bits((x.to_bits() as i64 + step) as u64);
        if negative { -x } else { x }
    })
}

/// Doubles within 2⁻²⁰ relative of the edge of the fast range, both sides.
fn near_the_fast_range() -> impl Strategy<Value = f64> {
    (any::<bool>(), -(1i64 << 32)..(1i64 << 32)).prop_map(|(negative, step)| {
        let x = f64::from_bits((trig::FAST_RANGE.to_bits() as i64 + step) as u64);
        if negative { -x } else { x }
    })
}

fn config(cases: u32) -> Config {
    Config { cases, rng_seed: RngSeed::Fixed(12), failure_persistence: None, ..Config::default() }
}

proptest! {
    #![proptest_config(config(20_000))]
    #[test]
    fn ref_every_finite_double(x in any_finite()) {
        check(x)?;
    }

    #[test]
    fn ref_next_to_multiples_of_half_pi(x in near_multiples_of_half_pi()) {
        check(x)?;
    }

    #[test]
    fn ref_at_the_edge_of_the_fast_range(x in near_the_fast_range()) {
        check(x)?;
    }
}

/// Hard and named arguments with their sine and cosine correctly rounded, by mpmath at 1500
/// bits (`reference/trig_hard_cases.py`): huge values, the largest double, the double nearest
/// a multiple of π/2 (6381956970095103·2⁷⁹⁷, whose cosine is −4.7e-19: glibc 2.36 gives it 8
/// ulp off), the doubles nearest π/2 and π, the fast range's edge, the smallest doubles, and
/// their neighbours.
#[rustfmt::skip]
#[allow(clippy::approx_constant)] // the doubles nearest π/2 and π, as the script prints them
const HARD: [(f64, f64, f64); 29] = [
    (1e+17, -0.4645301048353727, -0.8855573282976307),
    (1.0000000000000002e+17, 0.6998165507051524, 0.7143226129411997),
    (9.999999999999998e+16, 0.18990676687726846, 0.9818021286869482),
    (1e+22, -0.8522008497671888, 0.523214785395139),
    (1.0000000000000002e+22, -0.3396317409328751, 0.9405584939550036),
    (9.999999999999998e+21, -0.9924409679936447, -0.1227229605568478),
    (1e+300, -0.8178819121159085, -0.5753861119575491),
    (1.0000000000000002e+300, -0.7337461724215215, -0.6794236928874109),
    (9.999999999999999e+299, -0.8873754056066426, -0.46104760006364465),
    (1.7976931348623157e+308, 0.004961954789184062, -0.9999876894265599),
    (1.7976931348623155e+308, 0.927027925433735, 0.37499230054232496),
    (5.319372648326541e+255, 1.0, -4.687165924254628e-19),
    (5.319372648326542e+255, -0.6116218779093976, -0.7911502249652603),
    (5.3193726483265406e+255, -0.6116218779093976, 0.7911502249652603),
    (1.5707963267948966, 1.0, 6.123233995736766e-17),
    (1.5707963267948968, 1.0, -1.6081226496766366e-16),
    (1.5707963267948963, 1.0, 2.83276944882399e-16),
    (3.141592653589793, 1.2246467991473532e-16, -1.0),
    (3.1415926535897936, -3.216245299353273e-16, -1.0),
    (3.1415926535897927, 5.66553889764798e-16, -1.0),
    (1048576.0, 0.3304931400217347, 0.943808393901312),
    (1048576.0000000002, 0.3304931402414822, 0.9438083938243631),
    (1048575.9999999999, 0.3304931399118609, 0.9438083939397864),
    (2.2250738585072014e-308, 2.2250738585072014e-308, 1.0),
    (2.225073858507202e-308, 2.225073858507202e-308, 1.0),
    (2.225073858507201e-308, 2.225073858507201e-308, 1.0),
    (5e-324, 5e-324, 1.0),
    (1e-323, 1e-323, 1.0),
    (0.0, 0.0, 1.0),
];

/// Every variant within 1 ulp of the correctly rounded values beyond the fast range, within
/// 2 ulp plus [`FAST_ABSOLUTE`] in it; the exact reduction within 1 ulp everywhere; for x and −x.
#[test]
fn ref_hard_cases_against_mpmath() {
    for (x, sin, cos) in HARD.iter().flat_map(|&(x, s, c)| [(x, s, c), (-x, -s, c)]) {
        let within = |got: f64, want: f64| {
            if trig::is_fast(x) {
                ulps(got, want) <= 2 || (got - want).abs() <= 2.0 * ulp(want) + FAST_ABSOLUTE
            } else {
                ulps(got, want) <= 1
            }
        };
        let (plain, fused, exact) =
            (trig::sin_cos(x), trig::sin_cos_with::<true, true>(x), trig::exact::sin_cos(x));
        for (name, got, want) in [
            ("sin_cos sin", plain.0, sin),
            ("sin_cos cos", plain.1, cos),
            ("fused sin_cos sin", fused.0, sin),
            ("fused sin_cos cos", fused.1, cos),
            ("sin", trig::sin(x), sin),
            ("fused sin", trig::sin_with::<true, true>(x), sin),
        ] {
            assert!(within(got, want), "{name}({x:e}) = {got:e}, mpmath {want:e}: {} ulp", ulps(got, want));
        }
        assert!(ulps(exact.0, sin) <= 1 && ulps(exact.1, cos) <= 1, "exact::sin_cos({x:e}) = {exact:?}");
    }
}

/// NaN and ±∞ give NaN, as the platform's functions do.
#[test]
fn non_finite_arguments_give_nan() {
    for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert!(x.sin().is_nan() && x.cos().is_nan());
        let (s, c) = trig::sin_cos(x);
        let (fs, fc) = trig::sin_cos_with::<true, true>(x);
        let e = trig::exact::sin_cos(x);
        for v in [s, c, fs, fc, trig::sin(x), trig::sin_with::<true, true>(x), e.0, e.1] {
            assert!(v.is_nan(), "{x}: {v}");
        }
    }
}
