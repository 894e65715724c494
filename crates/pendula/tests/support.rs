//! Helpers shared by the test modules.

use pendula::integrator::Method;
use pendula::observe::Ignore;
use pendula::system::Values;
use pendula::{End, Error, RunSpec};

/// Validated values of a catalogued system with some settings.
pub fn values(system: &str, settings: &[(&str, f64)]) -> Values {
    let info = pendula::model::find(system).unwrap();
    let settings: Vec<(String, f64)> = settings.iter().map(|(n, v)| (n.to_string(), *v)).collect();
    info.values(&settings).unwrap()
}

/// Final state of `method` on the catalogued system from its initial values.
pub fn final_state(values: &Values, method: &Method, h: f64, t_end: f64) -> Result<Vec<f64>, Error> {
    let model = values.build();
    let spec = RunSpec { t0: 0.0, h, end: End::Time(t_end) };
    Ok(model.solve(method, values.initial_state(), &spec, &mut Ignore)?.state)
}

/// Largest absolute componentwise difference.
pub fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// A deterministic sequence in [lo, hi) (a 64-bit LCG; no test depends on its quality).
pub fn samples(n: usize, lo: f64, hi: f64) -> impl Iterator<Item = f64> {
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
    (0..n).map(move |_| {
        s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        lo + (hi - lo) * ((s >> 11) as f64 / (1u64 << 53) as f64)
    })
}
