//! The damped, driven pendulum in the dimensionless form of Baker and Gollub, and its
//! classic regimes as named [`PRESETS`].
//!
//! Reference: G. L. Baker and J. P. Gollub, *Chaotic Dynamics: An Introduction*, 2nd ed.,
//! Cambridge University Press (1996), ch. 3 and 4:
//! dω/dt = −ω/q − sin θ + g cos(ω_D t), with time in units of 1/ω₀ = √(l/g_grav) and
//! q = 2, ω_D = 2/3 throughout their study, the drive amplitude g choosing the regime.

use super::pendulum::PendulumForm;
use super::{Domain, Energy, Equations, Model, Quantity, System, SystemInfo, Values};
use crate::num::Num;

/// The damped, driven pendulum θ'' = −θ'/q − sin θ + g cos(ω_D t), dimensionless: time in
/// units of 1/ω₀, energy in units of m g l.
///
/// State y = (θ, ω). Damped, so it has no Hamiltonian form; its Lyapunov spectrum sums to
/// the trace of the Jacobian, −1/q.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrivenPendulum<T = f64> {
    /// Quality factor q (the damping rate is 1/q).
    pub q: T,
    /// Drive amplitude g.
    pub drive_amplitude: T,
    /// Drive angular frequency ω_D, in units of ω₀.
    pub drive_frequency: T,
}

/// Catalogue entry of [`DrivenPendulum`]; the defaults are Baker and Gollub's chaotic
/// regime (q = 2, g = 1.5, ω_D = 2/3).
pub static INFO: SystemInfo = SystemInfo {
    name: "driven-pendulum",
    description: "damped driven pendulum w' = -w/q - sin th + g cos(wD t), dimensionless (Baker & Gollub 1996)",
    parameters: &[
        Quantity {
            name: "q",
            unit: "1",
            default: 2.0,
            domain: Domain::Positive,
            description: "quality factor (damping rate 1/q)",
        },
        Quantity {
            name: "drive_amplitude",
            unit: "1",
            default: 1.5,
            domain: Domain::Real,
            description: "drive amplitude g (in units of m g l)",
        },
        Quantity {
            name: "drive_frequency",
            unit: "1",
            default: 2.0 / 3.0,
            domain: Domain::Positive,
            description: "drive angular frequency wD (in units of the small-angle frequency)",
        },
    ],
    state: &[
        Quantity {
            name: "theta",
            unit: "rad",
            default: 0.2,
            domain: Domain::Real,
            description: "angle from the downward vertical",
        },
        Quantity {
            name: "omega",
            unit: "1",
            default: 0.0,
            domain: Domain::Real,
            description: "angular velocity (in units of the small-angle frequency)",
        },
    ],
    variant: None,
    dimensionless: true,
    study_periods: 1.6,
    energy_scale: "1 (m g l, from hanging at rest to horizontal), or E(0) - V_min if larger",
};

/// A named set of values for a catalogued system, with where it comes from.
#[derive(Debug, Clone, Copy)]
pub struct Preset {
    /// Name used on the command line (`--preset`).
    pub name: &'static str,
    /// The system it applies to.
    pub system: &'static str,
    /// (name, value) settings applied over the system's defaults.
    pub settings: &'static [(&'static str, f64)],
    /// What to expect, in words.
    pub description: &'static str,
    /// The source of the values.
    pub source: &'static str,
}

const BAKER_GOLLUB: &str =
    "Baker & Gollub, Chaotic Dynamics: An Introduction, 2nd ed. (1996), ch. 3-4: q = 2, wD = 2/3";

/// Every preset, in the order `pendula list presets` shows them: the regimes of Baker and
/// Gollub's driven pendulum as the drive amplitude g rises (each checked by the sign of its
/// largest Lyapunov exponent in the tests).
pub static PRESETS: &[Preset] = &[
    Preset {
        name: "baker-gollub-periodic",
        system: "driven-pendulum",
        settings: &[("q", 2.0), ("drive_amplitude", 0.9), ("drive_frequency", 2.0 / 3.0)],
        description: "g = 0.9: periodic, one cycle per drive period",
        source: BAKER_GOLLUB,
    },
    Preset {
        name: "baker-gollub-period-2",
        system: "driven-pendulum",
        settings: &[("q", 2.0), ("drive_amplitude", 1.07), ("drive_frequency", 2.0 / 3.0)],
        description: "g = 1.07: period doubled, two drive periods per cycle",
        source: BAKER_GOLLUB,
    },
    Preset {
        name: "baker-gollub-chaotic",
        system: "driven-pendulum",
        settings: &[("q", 2.0), ("drive_amplitude", 1.15), ("drive_frequency", 2.0 / 3.0)],
        description: "g = 1.15: chaotic",
        source: BAKER_GOLLUB,
    },
    Preset {
        name: "baker-gollub-chaotic-1.5",
        system: "driven-pendulum",
        settings: &[("q", 2.0), ("drive_amplitude", 1.5), ("drive_frequency", 2.0 / 3.0)],
        description: "g = 1.5: chaotic, the book's strange attractor (the system's defaults)",
        source: BAKER_GOLLUB,
    },
];

/// Looks a preset up by name.
pub fn find_preset(name: &str) -> Result<&'static Preset, crate::Error> {
    PRESETS.iter().find(|p| p.name == name).ok_or_else(|| crate::Error::UnknownPreset {
        name: name.to_owned(),
        valid: PRESETS.iter().map(|p| p.name).collect::<Vec<_>>().join(", "),
        suggestions: crate::error::suggestions(name, PRESETS.iter().map(|p| p.name)),
    })
}

/// The equations, written once over every number type.
impl<T: Num> DrivenPendulum<T> {
    /// The drive g cos(ω_D t).
    #[inline(always)]
    fn drive(&self, t: T) -> T {
        self.drive_amplitude * (self.drive_frequency * t).cos()
    }

    /// ω' = −ω/q − sin θ + g c, from c = cos(ω_D t): the ensemble engine's stroboscopic
    /// kernel (`crate::ensemble::driven`) takes the cosine from a table shared by its lanes.
    #[inline(always)]
    pub fn acceleration(&self, theta: T, omega: T, cos_phase: T) -> T {
        -omega / self.q - theta.sin() + self.drive_amplitude * cos_phase
    }
}

/// θ' = ω, ω' = −ω/q − sin θ + g cos(ω_D t).
impl<T: Num> Equations<T> for DrivenPendulum<T> {
    #[inline(always)]
    fn rhs(&self, t: T, y: &[T], dydt: &mut [T]) {
        dydt[0] = y[1];
        dydt[1] = self.acceleration(y[0], y[1], (self.drive_frequency * t).cos());
    }

    /// 2 |θ| and the drive's phase ω_D t.
    #[inline(always)]
    fn trig_reach(&self, t: T, y: &[T]) -> T {
        super::reach(&y[..1]).max((self.drive_frequency * t).abs())
    }
}

/// The gradient of the conservative part H = p²/2 − cos θ − g θ cos(ω_D t): the damping
/// (1/q > 0 always) leaves the system without a Hamiltonian form
/// ([`Model::hamiltonian_form`] says so), so nothing runs Tao's map on it.
impl<T: Num> super::Canonical<T> for DrivenPendulum<T> {
    #[inline(always)]
    fn gradient(&self, t: T, q: &[T], p: &[T], dq: &mut [T], dp: &mut [T]) {
        dq[0] = q[0].sin() - self.drive_amplitude * (self.drive_frequency * t).cos();
        dp[0] = p[0];
    }
}

impl Model for DrivenPendulum {
    /// Never built: the damped pendulum has no Hamiltonian form.
    type Form = PendulumForm;
    const INFO: &'static SystemInfo = &INFO;
    const DIM: usize = 2;

    fn autonomous(&self) -> bool {
        self.drive_amplitude == 0.0
    }

    type Over<T: Num> = DrivenPendulum<T>;

    fn convert<T: Num>(&self, f: &dyn Fn(f64) -> T) -> DrivenPendulum<T> {
        DrivenPendulum {
            q: f(self.q),
            drive_amplitude: f(self.drive_amplitude),
            drive_frequency: f(self.drive_frequency),
        }
    }

    fn over<T: Num>(_: &dyn Fn(&str) -> f64, v: &dyn Fn(&str) -> T) -> DrivenPendulum<T> {
        DrivenPendulum {
            q: v("q"),
            drive_amplitude: v("drive_amplitude"),
            drive_frequency: v("drive_frequency"),
        }
    }

    fn from_values(v: &Values) -> Self {
        Self::over(&|n| v.get(n), &|n| v.get(n))
    }

    fn hamiltonian_form(&self) -> Result<PendulumForm, String> {
        Err(format!("the driven pendulum is damped (q = {}) and so not Hamiltonian", self.q))
    }

    /// p = ω in these units.
    fn to_momenta(&self, y: &[f64], z: &mut [f64]) {
        z[..2].copy_from_slice(&y[..2]);
    }

    fn to_velocities(&self, z: &[f64], y: &mut [f64]) {
        y[..2].copy_from_slice(&z[..2]);
    }

    /// 2π: time is in units of 1/ω₀.
    fn time_scale(&self) -> f64 {
        std::f64::consts::TAU
    }

    /// In units of m g l: 1, or the energy above the bottom (−1) when larger.
    fn energy_scale(&self, y0: &[f64]) -> f64 {
        (Energy::energy(self, 0.0, y0) + 1.0).max(1.0)
    }

    /// ω (g cos(ω_D t) − ω/q), in units of m g l ω₀.
    fn power(&self, t: f64, y: &[f64]) -> f64 {
        y[1] * (self.drive(t) - y[1] / self.q)
    }
}

impl System for DrivenPendulum {
    fn dim(&self) -> usize {
        2
    }

    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        Equations::rhs(self, t, y, dydt);
    }

    fn jacobian(&self, _t: f64, y: &[f64], jac: &mut [f64]) -> bool {
        jac.copy_from_slice(&[0.0, 1.0, -y[0].cos(), -1.0 / self.q]);
        true
    }
}

impl Energy for DrivenPendulum {
    /// ½ ω² − cos θ, in units of m g l (−1 at rest at the bottom).
    fn energy(&self, _t: f64, y: &[f64]) -> f64 {
        0.5 * y[1] * y[1] - y[0].cos()
    }
}
