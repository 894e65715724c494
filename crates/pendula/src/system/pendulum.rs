//! The simple pendulum θ'' = −(g/l) sin θ − b θ' + A cos(Ω t): the paper's §3 and §5, with
//! its exact period and exact solution through Jacobi elliptic functions.

use std::f64::consts::{PI, TAU};

use super::{Domain, Energy, Equations, Hamiltonian, Model, Quantity, System, SystemInfo, Values};
use crate::num::Num;
use crate::special::{ellip_f, ellip_k, jacobi};

/// A point mass on a massless rigid rod, with optional damping, drive and small-angle form.
///
/// State y = (θ, ω): angle from the downward vertical (rad) and angular velocity (rad/s).
/// The potential is V = −m g l cos θ (zero at the pivot's height, so V(0) = −m g l; see
/// ERRATA), and m g l (θ²/2 − 1), its small-angle expansion, when `linear` is set. The
/// parameters are of any [`Num`] type (its equations are written once, [`Equations`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pendulum<T = f64> {
    /// Bob mass m, kg (scales energy and momentum, not the motion).
    pub m: T,
    /// Rod length l, m.
    pub l: T,
    /// Gravitational acceleration g, m/s².
    pub g: T,
    /// Damping rate b in θ'' = … − b θ', 1/s.
    pub damping: T,
    /// Amplitude A of the driving angular acceleration A cos(Ω t), rad/s².
    pub drive_amplitude: T,
    /// Angular frequency Ω of the drive, rad/s.
    pub drive_frequency: T,
    /// Small-angle form: sin θ replaced by θ.
    pub linear: bool,
}

/// Catalogue entry of [`Pendulum`].
pub static INFO: SystemInfo = SystemInfo {
    name: "pendulum",
    description: "simple pendulum th'' = -(g/l) sin th - b th' + A cos(W t) (paper §3, §5)",
    parameters: &[
        Quantity { name: "m", unit: "kg", default: 1.0, domain: Domain::Positive, description: "bob mass" },
        Quantity { name: "l", unit: "m", default: 1.0, domain: Domain::Positive, description: "rod length" },
        Quantity {
            name: "g",
            unit: "m/s^2",
            default: 9.81,
            domain: Domain::Positive,
            description: "gravitational acceleration",
        },
        Quantity {
            name: "damping",
            unit: "1/s",
            default: 0.0,
            domain: Domain::NonNegative,
            description: "damping rate b",
        },
        Quantity {
            name: "drive_amplitude",
            unit: "rad/s^2",
            default: 0.0,
            domain: Domain::Real,
            description: "amplitude A of the driving angular acceleration",
        },
        Quantity {
            name: "drive_frequency",
            unit: "rad/s",
            default: 0.0,
            domain: Domain::NonNegative,
            description: "angular frequency W of the drive",
        },
        Quantity {
            name: "linear",
            unit: "1",
            default: 0.0,
            domain: Domain::Flag,
            description: "1 for the small-angle form sin th = th",
        },
    ],
    state: &[
        Quantity {
            name: "theta",
            unit: "rad",
            default: PI / 3.0,
            domain: Domain::Real,
            description: "angle from the downward vertical",
        },
        Quantity {
            name: "omega",
            unit: "rad/s",
            default: 0.0,
            domain: Domain::Real,
            description: "angular velocity",
        },
    ],
    variant: None,
    dimensionless: false,
    study_periods: 5.0,
    energy_scale: "m g l, the potential energy gained from hanging at rest to horizontal, or E(0) - V_min if larger",
};

impl Pendulum {
    /// Small-oscillation angular frequency ω₀ = √(g/l), rad/s.
    pub fn natural_frequency(&self) -> f64 {
        (self.g / self.l).sqrt()
    }

    /// Small-angle period 2π √(l/g), s.
    pub fn small_angle_period(&self) -> f64 {
        TAU / self.natural_frequency()
    }

    /// Exact period, s, of the undamped, undriven motion released from rest at `amplitude`
    /// (rad, 0 ≤ amplitude < π): 4 √(l/g) K(sin(θ₀/2)) (Landau & Lifshitz §11). It grows
    /// without bound as the amplitude approaches π. For the linear form it is 2π √(l/g).
    pub fn period(&self, amplitude: f64) -> f64 {
        if self.linear {
            return self.small_angle_period();
        }
        4.0 / self.natural_frequency() * ellip_k((0.5 * amplitude).sin())
    }

    /// Exact state (θ, ω) at time t (s) from (θ₀, ω₀) at t = 0, when there is neither
    /// damping nor drive (`None` otherwise, or exactly on the separatrix).
    ///
    /// With k² = sin²(θ₀/2) + ω₀²/(4ω₀'²) (ω₀' = √(g/l)): for k < 1 the pendulum librates,
    /// sin(θ/2) = k sn(ω₀' t + u₀, k); for k > 1 it rotates, θ/2 = ±am(k ω₀' t + v₀, 1/k).
    pub fn exact(&self, t: f64, theta0: f64, omega0: f64) -> Option<(f64, f64)> {
        if self.damping != 0.0 || self.drive_amplitude != 0.0 {
            return None;
        }
        let wn = self.natural_frequency();
        if self.linear {
            let (s, c) = (wn * t).sin_cos();
            return Some((theta0 * c + omega0 / wn * s, -theta0 * wn * s + omega0 * c));
        }
        // Work with θ₀ reduced to (−π, π]; the motion is 2π-periodic in θ.
        let offset = TAU * (theta0 / TAU).round();
        let th = theta0 - offset;
        let half = (0.5 * th).sin();
        let k2 = half * half + omega0 * omega0 / (4.0 * wn * wn);
        if k2 < 1.0 {
            let k = k2.sqrt();
            let u_start = ellip_f((half / k).clamp(-1.0, 1.0).asin(), k);
            // sn is the same at u and 2K − u, cn changes sign: pick the branch whose cn has ω₀'s sign.
            let u0 = if omega0 < 0.0 { 2.0 * ellip_k(k) - u_start } else { u_start };
            let j = jacobi(u0 + wn * t, k);
            Some((offset + 2.0 * (k * j.sn).asin(), 2.0 * k * wn * j.cn))
        } else if k2 > 1.0 {
            let kr = k2.sqrt();
            let dir = omega0.signum();
            let v0 = ellip_f(dir * 0.5 * th, 1.0 / kr);
            let j = jacobi(v0 + kr * wn * t, 1.0 / kr);
            Some((offset + dir * 2.0 * j.am, dir * 2.0 * kr * wn * j.dn))
        } else {
            None
        }
    }

    /// d/dθ of [`Pendulum::gravity_term`].
    fn gravity_slope(&self, theta: f64) -> f64 {
        if self.linear { 1.0 } else { theta.cos() }
    }

    fn potential(&self, theta: f64) -> f64 {
        let mgl = self.m * self.g * self.l;
        if self.linear { mgl * (0.5 * theta * theta - 1.0) } else { -mgl * theta.cos() }
    }
}

/// The equations, written once over every number type.
impl<T: Num> Pendulum<T> {
    /// sin θ, or θ in the small-angle form.
    #[inline(always)]
    fn gravity_term(&self, theta: T) -> T {
        if self.linear { theta } else { theta.sin() }
    }

    /// The driving angular acceleration A cos(Ω t), rad/s².
    #[inline(always)]
    fn drive(&self, t: T) -> T {
        if self.drive_amplitude.is_zero() {
            T::splat(0.0)
        } else {
            self.drive_amplitude * (self.drive_frequency * t).cos()
        }
    }
}

/// θ' = ω, ω' = −(g/l) sin θ − b ω + A cos(Ω t).
impl<T: Num> Equations<T> for Pendulum<T> {
    #[inline(always)]
    fn rhs(&self, t: T, y: &[T], dydt: &mut [T]) {
        dydt[0] = y[1];
        dydt[1] = -self.g / self.l * self.gravity_term(y[0]) - self.damping * y[1] + self.drive(t);
    }

    /// 2 |θ| and the drive's phase Ω t.
    #[inline(always)]
    fn trig_reach(&self, t: T, y: &[T]) -> T {
        let angle = super::reach(&y[..1]);
        if self.drive_amplitude.is_zero() { angle } else { angle.max((self.drive_frequency * t).abs()) }
    }
}

/// ∂H/∂θ = m l² ((g/l) sin θ − A cos(Ω t)), ∂H/∂p = p / (m l²) (the form exists undamped).
impl<T: Num> super::Canonical<T> for Pendulum<T> {
    #[inline(always)]
    fn gradient(&self, t: T, q: &[T], p: &[T], dq: &mut [T], dp: &mut [T]) {
        let ml2 = self.m * self.l * self.l;
        dq[0] = ml2 * (self.g / self.l * self.gravity_term(q[0]) - self.drive(t));
        dp[0] = p[0] / ml2;
    }
}

impl Model for Pendulum {
    type Form = PendulumForm;
    const INFO: &'static SystemInfo = &INFO;
    const DIM: usize = 2;
    type Over<T: Num> = Pendulum<T>;

    fn convert<T: Num>(&self, f: &dyn Fn(f64) -> T) -> Pendulum<T> {
        Pendulum {
            m: f(self.m),
            l: f(self.l),
            g: f(self.g),
            damping: f(self.damping),
            drive_amplitude: f(self.drive_amplitude),
            drive_frequency: f(self.drive_frequency),
            linear: self.linear,
        }
    }

    fn over<T: Num>(setting: &dyn Fn(&str) -> f64, v: &dyn Fn(&str) -> T) -> Pendulum<T> {
        Pendulum {
            m: v("m"),
            l: v("l"),
            g: v("g"),
            damping: v("damping"),
            drive_amplitude: v("drive_amplitude"),
            drive_frequency: v("drive_frequency"),
            linear: setting("linear") == 1.0,
        }
    }

    fn autonomous(&self) -> bool {
        self.drive_amplitude == 0.0
    }

    fn from_values(v: &Values) -> Self {
        Self::over(&|n| v.get(n), &|n| v.get(n))
    }

    fn hamiltonian_form(&self) -> Result<PendulumForm, String> {
        if self.damping != 0.0 {
            return Err(format!("the pendulum with damping = {} is not Hamiltonian", self.damping));
        }
        Ok(PendulumForm { pendulum: *self })
    }

    fn to_momenta(&self, y: &[f64], z: &mut [f64]) {
        z[0] = y[0];
        z[1] = self.m * self.l * self.l * y[1];
    }

    fn to_velocities(&self, z: &[f64], y: &mut [f64]) {
        y[0] = z[0];
        y[1] = z[1] / (self.m * self.l * self.l);
    }

    /// 2π √(l/g).
    fn time_scale(&self) -> f64 {
        std::f64::consts::TAU * (self.l / self.g).sqrt()
    }

    fn energy_scale(&self, y0: &[f64]) -> f64 {
        let above_min = Energy::energy(self, 0.0, y0) - self.potential(0.0);
        (self.m * self.g * self.l).max(above_min)
    }

    /// m l² ω (A cos(Ω t) − b ω): the drive and the damping act on the angular acceleration.
    fn power(&self, t: f64, y: &[f64]) -> f64 {
        self.m * self.l * self.l * y[1] * (self.drive(t) - self.damping * y[1])
    }

    fn exact(&self, t: f64, y0: &[f64], y: &mut [f64]) -> bool {
        match Pendulum::exact(self, t, y0[0], y0[1]) {
            Some((theta, omega)) => {
                (y[0], y[1]) = (theta, omega);
                true
            }
            None => false,
        }
    }
}

impl System for Pendulum {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        Equations::rhs(self, t, y, dydt);
    }
    fn jacobian(&self, _t: f64, y: &[f64], jac: &mut [f64]) -> bool {
        jac.copy_from_slice(&[0.0, 1.0, -self.g / self.l * self.gravity_slope(y[0]), -self.damping]);
        true
    }
}

impl Energy for Pendulum {
    fn energy(&self, _t: f64, y: &[f64]) -> f64 {
        0.5 * self.m * self.l * self.l * y[1] * y[1] + self.potential(y[0])
    }
}

/// The undamped pendulum on (θ, p = m l² ω) (paper (26)–(30)):
/// H = p²/(2 m l²) + V(θ) − m l² A cos(Ω t) θ, separable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PendulumForm {
    /// The pendulum (with no damping).
    pub pendulum: Pendulum,
}

impl System for PendulumForm {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        super::hamilton_rhs(self, t, y, dydt);
    }
    /// (θ' = p/(m l²), p' = −m g l sin θ + m l² τ(t)).
    fn jacobian(&self, _t: f64, y: &[f64], jac: &mut [f64]) -> bool {
        let s = &self.pendulum;
        let ml2 = s.m * s.l * s.l;
        jac.copy_from_slice(&[0.0, 1.0 / ml2, -ml2 * s.g / s.l * s.gravity_slope(y[0]), 0.0]);
        true
    }
}

impl Hamiltonian for PendulumForm {
    fn dh_dq(&self, t: f64, q: &[f64], p: &[f64], out: &mut [f64]) {
        super::Canonical::gradient(&self.pendulum, t, q, p, out, &mut [0.0]);
    }
    fn dh_dp(&self, t: f64, q: &[f64], p: &[f64], out: &mut [f64]) {
        super::Canonical::gradient(&self.pendulum, t, q, p, &mut [0.0], out);
    }
    fn separable(&self) -> bool {
        true
    }
}

impl Energy for PendulumForm {
    fn energy(&self, _t: f64, y: &[f64]) -> f64 {
        let s = &self.pendulum;
        0.5 * y[1] * y[1] / (s.m * s.l * s.l) + s.potential(y[0])
    }
}
