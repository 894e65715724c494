//! The systems test kit (`pendula::kit`) passes on every catalogued system and variant, and
//! fails on a system with a planted error.

use pendula::kit;
use pendula::model::CATALOGUE;
use pendula::num::Num;
use pendula::system::double::{DoublePendulum, DoublePendulumForm};
use pendula::system::{Energy, Model, System, SystemInfo, Values};

use crate::support::values;

#[test]
fn every_catalogued_system_passes_the_kit() {
    let mut all: Vec<Values> = CATALOGUE.iter().map(|e| e.values(&[]).unwrap()).collect();
    // Moving states, forces and structure.
    all.push(values("double", &[("damping", 0.3), ("omega1", 1.5), ("omega2", -0.7)]));
    all.push(values("double", &[("drive_amplitude", 2.0), ("drive_frequency", 3.0), ("omega2", 2.0)]));
    all.push(values(
        "pendulum",
        &[("damping", 0.2), ("drive_amplitude", 1.0), ("drive_frequency", 2.0), ("omega", 0.4)],
    ));
    all.push(values("pendulum", &[("linear", 1.0), ("omega", 1.0)]));
    all.push(values(
        "oscillator",
        &[("c", 0.4), ("drive_amplitude", 1.0), ("drive_frequency", 1.3), ("v", 0.5)],
    ));
    all.push(values("chain", &[("links", 5.0), ("m3", 2.0), ("l2", 0.5), ("omega1", 1.0), ("omega4", -2.0)]));
    all.push(values("chain", &[("links", 1.0)]));
    all.push(values("driven-pendulum", &[("omega", 0.5)]));
    for v in &all {
        let entry = CATALOGUE.iter().find(|e| e.name == v.info().name).unwrap();
        let failures = entry.check(v);
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    }
    // Every entry was checked.
    for entry in CATALOGUE {
        assert!(all.iter().any(|v| v.info().name == entry.name), "{} not checked", entry.name);
    }
}

/// A test-only system: the double pendulum with a wrong sign planted in its Jacobian.
#[derive(Debug, Clone, Copy)]
struct WrongJacobian(DoublePendulum);

static BROKEN: SystemInfo = SystemInfo { name: "broken", ..pendula::system::double::INFO };

impl System for WrongJacobian {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        self.0.rhs(t, y, dydt);
    }
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) -> bool {
        self.0.jacobian(t, y, jac);
        // ∂θ₁''/∂θ₁ with the wrong sign.
        jac[8] = -jac[8];
        true
    }
}

impl Energy for WrongJacobian {
    fn energy(&self, t: f64, y: &[f64]) -> f64 {
        self.0.energy(t, y)
    }
}

impl Model for WrongJacobian {
    type Form = DoublePendulumForm;
    const INFO: &'static SystemInfo = &BROKEN;
    const DIM: usize = 4;
    type Over<T: Num> = DoublePendulum<T>;
    fn over<T: Num>(setting: &dyn Fn(&str) -> f64, value: &dyn Fn(&str) -> T) -> DoublePendulum<T> {
        DoublePendulum::over(setting, value)
    }
    fn convert<T: Num>(&self, f: &dyn Fn(f64) -> T) -> DoublePendulum<T> {
        self.0.convert(f)
    }
    fn from_values(values: &Values) -> Self {
        WrongJacobian(DoublePendulum::from_values(values))
    }
    fn hamiltonian_form(&self) -> Result<DoublePendulumForm, String> {
        self.0.hamiltonian_form()
    }
    fn to_momenta(&self, y: &[f64], z: &mut [f64]) {
        self.0.to_momenta(y, z);
    }
    fn to_velocities(&self, z: &[f64], y: &mut [f64]) {
        self.0.to_velocities(z, y);
    }
    fn energy_scale(&self, y0: &[f64]) -> f64 {
        self.0.energy_scale(y0)
    }
    fn time_scale(&self) -> f64 {
        self.0.time_scale()
    }
}

#[test]
fn the_kit_catches_a_wrong_jacobian_sign() {
    let v = values("double", &[("omega1", 1.0)]);
    let failures = kit::check_values::<WrongJacobian>(&v);
    assert!(
        failures.iter().any(|f| f.contains("Jacobian J[2][0]")),
        "the planted sign is not caught: {failures:?}"
    );
    // The same system without the planted error passes.
    assert!(kit::check_values::<DoublePendulum>(&v).is_empty());
}
