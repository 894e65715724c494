//! What errors say: suggestions for misspelt names, short floats, and the resonance peak
//! the oscillator reports.

use pendula::Error;
use pendula::error::{Short, suggestions};
use pendula::system;
use pendula::system::oscillator::Oscillator;

#[test]
fn short_floats_round_to_ten_digits_and_read_back() {
    // 92 · 0.1 and 0.1 + 0.2 are one ulp off the decimal a person typed.
    assert_eq!(format!("{}", 92.0 * 0.1), "9.200000000000001");
    assert_eq!(Short(92.0 * 0.1).to_string(), "9.2");
    assert_eq!(Short(0.1 + 0.2).to_string(), "0.3");
    assert_eq!(Short(11.0 * 0.7).to_string(), "7.7");
    assert_eq!(Short(std::f64::consts::PI).to_string(), "3.141592654");
    assert_eq!(Short(-1.5e-7).to_string(), "-1.5e-7");
    assert_eq!(Short(2.5e20).to_string(), "2.5e20");
    assert_eq!(Short(131.6).to_string(), "131.6");
    assert_eq!(Short(0.0).to_string(), "0");
    assert_eq!(Short(f64::NAN).to_string(), "NaN");
    assert_eq!(Short(f64::NEG_INFINITY).to_string(), "-inf");
    assert_eq!(
        Error::NonFinite { t: 92.0 * 0.1 }.to_string(),
        "the state became non-finite at t = 9.2 s (try a smaller step)"
    );
}

#[test]
fn suggestions_are_the_closest_names_within_a_third_of_their_length() {
    let methods = pendula::integrator::METHODS.iter().map(|m| m.name);
    assert_eq!(suggestions("rk5", methods.clone()), ["rk4"]);
    assert_eq!(suggestions("Verlet", methods.clone()), ["verlet"]);
    assert_eq!(suggestions("dopri8", methods.clone()), ["dopri5"]);
    assert_eq!(
        suggestions("gauss-legendre", methods.clone()),
        ["gauss-legendre-2", "gauss-legendre-4", "gauss-legendre-6"]
    );
    assert!(suggestions("leapfrog", methods).is_empty());
    // Transposed neighbours are one edit (Damerau), not two.
    assert_eq!(suggestions("pnedulum", ["oscillator", "pendulum", "double"]), ["pendulum"]);
    // Replacing the only character is no misspelling.
    assert!(suggestions("y", ["x", "v"]).is_empty());
}

#[test]
fn lookups_carry_their_suggestions() {
    let Err(Error::UnknownSystem { suggestions, .. }) = pendula::model::find("dubble") else { panic!() };
    assert_eq!(suggestions, ["double"]);
    let err = pendula::model::find("pendulum").unwrap().quantity("omgea").unwrap_err();
    assert!(
        err.to_string().contains("unknown name `omgea` for system `pendulum` (did you mean `omega`?)"),
        "{err}"
    );
    let err = system::driven::find_preset("baker-gollub-period2").unwrap_err();
    assert!(err.to_string().contains("(did you mean `baker-gollub-period-2`?)"), "{err}");
    let err = pendula::model::find("tripple").unwrap_err();
    assert!(!err.to_string().contains("did you mean"), "{err}");
}

/// ω_r = ω₀ √(1 − 2ζ²) is where 1/√((k − mΩ²)² + (cΩ)²) peaks: checked against the
/// amplitude on a fine grid around it, and absent from ζ = 1/√2 on.
#[test]
fn ref_resonance_frequency_is_the_amplitude_maximum() {
    for (k, m, zeta) in [(4.0, 1.0, 0.1), (1.0, 2.0, 0.5), (9.0, 1.0, 0.7)] {
        let c = 2.0 * zeta * f64::sqrt(k * m);
        let w0 = f64::sqrt(k / m);
        let o = |w: f64| Oscillator { m, k, c, drive_amplitude: 1.0, drive_frequency: w };
        let wr = o(1.0).resonance_frequency().unwrap();
        assert!((wr - w0 * (1.0 - 2.0 * zeta * zeta).sqrt()).abs() < 1e-12 * w0);
        let amplitude = |w: f64| 1.0 / ((k - m * w * w).powi(2) + (c * w).powi(2)).sqrt();
        for d in [-1e-3, 1e-3] {
            assert!(amplitude(wr) > amplitude(wr * (1.0 + d)), "zeta {zeta}");
        }
        assert!((o(wr).steady_state().amplitude - amplitude(wr)).abs() < 1e-12 * amplitude(wr));
    }
    let overdamped = Oscillator { m: 1.0, k: 1.0, c: 2.0 * 0.71, drive_amplitude: 1.0, drive_frequency: 1.0 };
    assert_eq!(overdamped.resonance_frequency(), None);
}
