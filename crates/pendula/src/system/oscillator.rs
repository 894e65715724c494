//! The harmonic oscillator m x'' + c x' + k x = F cos(Ω t): the paper's §2, with its exact
//! solution in every damping regime and the forced steady state.

use super::{Domain, Energy, Equations, Hamiltonian, Model, Quantity, System, SystemInfo, Values};
use crate::num::Num;

/// A mass on a linear spring with viscous damping and a harmonic driving force.
///
/// State y = (x, v): displacement (m) and velocity (m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Oscillator<T = f64> {
    /// Mass m, kg.
    pub m: T,
    /// Spring constant k, N/m.
    pub k: T,
    /// Viscous damping coefficient c, N·s/m.
    pub c: T,
    /// Amplitude F of the driving force, N.
    pub drive_amplitude: T,
    /// Angular frequency Ω of the driving force, rad/s.
    pub drive_frequency: T,
}

/// Catalogue entry of [`Oscillator`].
pub static INFO: SystemInfo = SystemInfo {
    name: "oscillator",
    description: "harmonic oscillator m x'' + c x' + k x = F cos(W t) (paper §2)",
    parameters: &[
        Quantity { name: "m", unit: "kg", default: 1.0, domain: Domain::Positive, description: "mass" },
        Quantity {
            name: "k",
            unit: "N/m",
            default: 1.0,
            domain: Domain::Positive,
            description: "spring constant",
        },
        Quantity {
            name: "c",
            unit: "N s/m",
            default: 0.0,
            domain: Domain::NonNegative,
            description: "viscous damping coefficient",
        },
        Quantity {
            name: "drive_amplitude",
            unit: "N",
            default: 0.0,
            domain: Domain::Real,
            description: "amplitude F of the driving force",
        },
        Quantity {
            name: "drive_frequency",
            unit: "rad/s",
            default: 0.0,
            domain: Domain::NonNegative,
            description: "angular frequency W of the driving force",
        },
    ],
    state: &[
        Quantity { name: "x", unit: "m", default: 1.0, domain: Domain::Real, description: "displacement" },
        Quantity { name: "v", unit: "m/s", default: 0.0, domain: Domain::Real, description: "velocity" },
    ],
    variant: None,
    dimensionless: false,
    study_periods: 1.6,
    energy_scale: "E(0) (the energy above the minimum at x = 0) plus F^2/(2 k), the energy of the drive's static displacement; 1/2 k (1 m)^2 if both vanish",
};

/// The damping regime, from the damping ratio ζ = c / (2 √(k m)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Regime {
    /// ζ = 0: constant amplitude.
    Undamped,
    /// 0 < ζ < 1: decaying oscillation.
    Underdamped,
    /// ζ = 1: fastest return to rest without oscillation.
    CriticallyDamped,
    /// ζ > 1: slow return to rest without oscillation.
    Overdamped,
}

/// The forced steady state x_p(t) = amplitude · cos(Ω t − phase_lag).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteadyState {
    /// Amplitude X = F / √((k − m Ω²)² + (c Ω)²), m (infinite at undamped resonance).
    pub amplitude: f64,
    /// Phase lag φ behind the force, rad, in [0, π]; π/2 at resonance (ERRATA: not
    /// "slightly delayed").
    pub phase_lag: f64,
}

impl Oscillator {
    /// Natural angular frequency ω₀ = √(k/m), rad/s.
    pub fn natural_frequency(&self) -> f64 {
        (self.k / self.m).sqrt()
    }

    /// Damping ratio ζ = c / (2 √(k m)).
    pub fn damping_ratio(&self) -> f64 {
        self.c / (2.0 * (self.k * self.m).sqrt())
    }

    /// The damping regime.
    pub fn regime(&self) -> Regime {
        let zeta = self.damping_ratio();
        if zeta == 0.0 {
            Regime::Undamped
        } else if zeta < 1.0 {
            Regime::Underdamped
        } else if zeta == 1.0 {
            Regime::CriticallyDamped
        } else {
            Regime::Overdamped
        }
    }

    /// The drive frequency at which the steady-state amplitude peaks, rad/s: setting the
    /// derivative of 1/√((k − mΩ²)² + (cΩ)²) to zero gives ω_r = ω₀ √(1 − 2ζ²). `None` for
    /// ζ ≥ 1/√2, where the amplitude falls monotonically from its static value at Ω = 0.
    pub fn resonance_frequency(&self) -> Option<f64> {
        let zeta = self.damping_ratio();
        let square = 1.0 - 2.0 * zeta * zeta;
        (square > 0.0).then(|| self.natural_frequency() * square.sqrt())
    }

    /// Amplitude and phase lag of the forced steady state.
    pub fn steady_state(&self) -> SteadyState {
        let w = self.drive_frequency;
        let stiffness = self.k - self.m * w * w;
        let friction = self.c * w;
        SteadyState {
            amplitude: self.drive_amplitude / stiffness.hypot(friction),
            phase_lag: friction.atan2(stiffness),
        }
    }

    /// Exact solution (x, v) at time t (s) from (x₀, v₀) at t = 0, for every damping regime
    /// and any drive, including undamped resonance (where the amplitude grows linearly).
    pub fn exact(&self, t: f64, x0: f64, v0: f64) -> (f64, f64) {
        let (xp, vp, xp0, vp0) = self.particular(t);
        let (xh, vh) = self.homogeneous(t, x0 - xp0, v0 - vp0);
        (xh + xp, vh + vp)
    }

    /// A particular solution and its value at 0: (x_p(t), x_p'(t), x_p(0), x_p'(0)).
    fn particular(&self, t: f64) -> (f64, f64, f64, f64) {
        let (f, w) = (self.drive_amplitude, self.drive_frequency);
        if f == 0.0 {
            return (0.0, 0.0, 0.0, 0.0);
        }
        let w0 = self.natural_frequency();
        if self.c == 0.0 && w == w0 {
            // Resonance without damping: x_p = F/(2 m ω₀) · t sin(ω₀ t).
            let a = f / (2.0 * self.m * w0);
            let (s, c) = (w0 * t).sin_cos();
            return (a * t * s, a * (s + w0 * t * c), 0.0, 0.0);
        }
        let SteadyState { amplitude, phase_lag } = self.steady_state();
        let (s, c) = (w * t - phase_lag).sin_cos();
        (amplitude * c, -amplitude * w * s, amplitude * phase_lag.cos(), amplitude * w * phase_lag.sin())
    }

    /// Free motion x'' + 2γ x' + ω₀² x = 0 from (x₀, v₀), γ = c/(2m):
    /// x = e^{−γt} (x₀ C(t) + (v₀ + γ x₀) S(t)), with C, S = cos, sin(ω_d t)/ω_d when
    /// underdamped, cosh, sinh(β t)/β when overdamped and 1, t when critical. This form
    /// stays well conditioned near ζ = 1, where the textbook exponentials cancel.
    fn homogeneous(&self, t: f64, x0: f64, v0: f64) -> (f64, f64) {
        let gamma = self.c / (2.0 * self.m);
        // σ = γ² − ω₀²: −ω_d² (underdamped), β² (overdamped), 0 (critical). C' = σ S, S' = C.
        let sigma = gamma * gamma - self.k / self.m;
        let (cc, ss) = if sigma < 0.0 {
            let wd = (-sigma).sqrt();
            let (s, c) = (wd * t).sin_cos();
            (c, s / wd)
        } else if sigma > 0.0 {
            let beta = sigma.sqrt();
            ((beta * t).cosh(), (beta * t).sinh() / beta)
        } else {
            (1.0, t)
        };
        let b = v0 + gamma * x0;
        let decay = (-gamma * t).exp();
        let x = x0 * cc + b * ss;
        let v = x0 * sigma * ss + b * cc - gamma * x;
        (decay * x, decay * v)
    }
}

/// x' = v, v' = (F cos(Ω t) − c v − k x) / m.
impl<T: Num> Equations<T> for Oscillator<T> {
    #[inline(always)]
    fn rhs(&self, t: T, y: &[T], dydt: &mut [T]) {
        let force = self.drive_amplitude * (self.drive_frequency * t).cos();
        dydt[0] = y[1];
        dydt[1] = (force - self.c * y[1] - self.k * y[0]) / self.m;
    }

    /// The drive's phase Ω t, the only argument of a cosine here.
    #[inline(always)]
    fn trig_reach(&self, t: T, _y: &[T]) -> T {
        (self.drive_frequency * t).abs()
    }
}

/// ∂H/∂x = k x − F cos(Ω t), ∂H/∂p = p / m (the form exists undamped).
impl<T: Num> super::Canonical<T> for Oscillator<T> {
    #[inline(always)]
    fn gradient(&self, t: T, q: &[T], p: &[T], dq: &mut [T], dp: &mut [T]) {
        dq[0] = self.k * q[0] - self.drive_amplitude * (self.drive_frequency * t).cos();
        dp[0] = p[0] / self.m;
    }
}

impl Model for Oscillator {
    type Form = OscillatorForm;
    const INFO: &'static SystemInfo = &INFO;
    const DIM: usize = 2;

    fn autonomous(&self) -> bool {
        self.drive_amplitude == 0.0
    }

    type Over<T: Num> = Oscillator<T>;

    fn convert<T: Num>(&self, f: &dyn Fn(f64) -> T) -> Oscillator<T> {
        Oscillator {
            m: f(self.m),
            k: f(self.k),
            c: f(self.c),
            drive_amplitude: f(self.drive_amplitude),
            drive_frequency: f(self.drive_frequency),
        }
    }

    fn over<T: Num>(_: &dyn Fn(&str) -> f64, v: &dyn Fn(&str) -> T) -> Oscillator<T> {
        Oscillator {
            m: v("m"),
            k: v("k"),
            c: v("c"),
            drive_amplitude: v("drive_amplitude"),
            drive_frequency: v("drive_frequency"),
        }
    }

    fn from_values(v: &Values) -> Self {
        Self::over(&|n| v.get(n), &|n| v.get(n))
    }

    fn hamiltonian_form(&self) -> Result<OscillatorForm, String> {
        if self.c != 0.0 {
            return Err(format!("the oscillator with damping c = {} is not Hamiltonian", self.c));
        }
        Ok(OscillatorForm { oscillator: *self })
    }

    fn to_momenta(&self, y: &[f64], z: &mut [f64]) {
        z[0] = y[0];
        z[1] = self.m * y[1];
    }

    fn to_velocities(&self, z: &[f64], y: &mut [f64]) {
        y[0] = z[0];
        y[1] = z[1] / self.m;
    }

    /// 2π √(m/k).
    fn time_scale(&self) -> f64 {
        std::f64::consts::TAU * (self.m / self.k).sqrt()
    }

    fn energy_scale(&self, y0: &[f64]) -> f64 {
        let drive = self.drive_amplitude * self.drive_amplitude / (2.0 * self.k);
        let scale = Energy::energy(self, 0.0, y0) + drive;
        if scale > 0.0 { scale } else { 0.5 * self.k }
    }

    /// v (F cos(Ω t) − c v).
    fn power(&self, t: f64, y: &[f64]) -> f64 {
        y[1] * (self.drive_amplitude * (self.drive_frequency * t).cos() - self.c * y[1])
    }

    fn exact(&self, t: f64, y0: &[f64], y: &mut [f64]) -> bool {
        (y[0], y[1]) = Oscillator::exact(self, t, y0[0], y0[1]);
        true
    }
}

impl System for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        Equations::rhs(self, t, y, dydt);
    }
    fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut [f64]) -> bool {
        jac.copy_from_slice(&[0.0, 1.0, -self.k / self.m, -self.c / self.m]);
        true
    }
}

impl Energy for Oscillator {
    fn energy(&self, _t: f64, y: &[f64]) -> f64 {
        0.5 * self.m * y[1] * y[1] + 0.5 * self.k * y[0] * y[0]
    }
}

/// The undamped oscillator on (x, p = m v): H = p²/(2m) + k x²/2 − F cos(Ω t) x, separable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OscillatorForm {
    /// The oscillator (with c = 0).
    pub oscillator: Oscillator,
}

impl System for OscillatorForm {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        super::hamilton_rhs(self, t, y, dydt);
    }
    /// (q' = p/m, p' = −k q + F(t)).
    fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut [f64]) -> bool {
        jac.copy_from_slice(&[0.0, 1.0 / self.oscillator.m, -self.oscillator.k, 0.0]);
        true
    }
}

impl Hamiltonian for OscillatorForm {
    fn dh_dq(&self, t: f64, q: &[f64], p: &[f64], out: &mut [f64]) {
        super::Canonical::gradient(&self.oscillator, t, q, p, out, &mut [0.0]);
    }
    fn dh_dp(&self, t: f64, q: &[f64], p: &[f64], out: &mut [f64]) {
        super::Canonical::gradient(&self.oscillator, t, q, p, &mut [0.0], out);
    }
    fn separable(&self) -> bool {
        true
    }
}

impl Energy for OscillatorForm {
    fn energy(&self, _t: f64, y: &[f64]) -> f64 {
        let o = &self.oscillator;
        0.5 * y[1] * y[1] / o.m + 0.5 * o.k * y[0] * y[0]
    }
}
