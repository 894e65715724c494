//! Helpers shared by the test modules.

use pendula::integrator::Method;
use pendula::observe::Ignore;
use pendula::system::{self, Values};
use pendula::{End, Error, RunSpec};

/// Validated values of a catalogued system with some settings.
pub fn values(system: &str, settings: &[(&str, f64)]) -> Values {
    let info = system::find(system).unwrap();
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
