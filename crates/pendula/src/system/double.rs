//! The planar double pendulum: the paper's §6, Lagrangian form (matrix formalism (73)–(82))
//! and Hamiltonian form ((87), (88), (108), (109)).

use std::f64::consts::PI;

use num_dual::Dual64;

use super::{
    Domain, Energy, Equations, Hamiltonian, Model, Quantity, System, SystemInfo, Values, dual_jacobian,
};
use crate::num::Num;

/// Two point masses on massless rigid rods, the second hung from the first.
///
/// State y = (θ₁, θ₂, ω₁, ω₂): angles from the downward vertical (rad) and angular
/// velocities (rad/s). Its Hamiltonian (94) is not separable (the mass matrix depends on
/// θ₁ − θ₂), so explicit splitting methods do not apply: symplectic methods run on
/// [`DoublePendulumForm`].
///
/// The parameters are of any [`Num`] type `T`: `f64` for one pendulum, [`crate::num::Lanes`]
/// for a lane group of the ensemble engine (one pendulum per lane), dual numbers for
/// Jacobians. The equations of motion, the energy and the Hamiltonian gradient are written
/// once, over `T` ([`DoublePendulum::accelerations`], [`DoublePendulum::energy_from`],
/// [`DoublePendulum::hamiltonian_gradient`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DoublePendulum<T = f64> {
    /// Mass of the first bob m₁, kg.
    pub m1: T,
    /// Mass of the second bob m₂, kg.
    pub m2: T,
    /// Length of the first rod l₁, m.
    pub l1: T,
    /// Length of the second rod l₂, m.
    pub l2: T,
    /// Gravitational acceleration g, m/s².
    pub g: T,
    /// Viscous friction coefficient b at both joints, N m s/rad: torques −b θ̇₁ at the pivot
    /// and −b (θ̇₂ − θ̇₁) at the elbow (on the second rod; its reaction on the first).
    pub damping: T,
    /// Amplitude A of the driving torque A cos(Ω t) on the first rod, N m.
    pub drive_amplitude: T,
    /// Angular frequency Ω of the drive, rad/s.
    pub drive_frequency: T,
}

impl Default for DoublePendulum {
    /// The catalogue's defaults: unit masses and lengths, g = 9.81 m/s², no damping or drive.
    fn default() -> Self {
        DoublePendulum {
            m1: 1.0,
            m2: 1.0,
            l1: 1.0,
            l2: 1.0,
            g: 9.81,
            damping: 0.0,
            drive_amplitude: 0.0,
            drive_frequency: 0.0,
        }
    }
}

/// Catalogue entry of [`DoublePendulum`].
pub static INFO: SystemInfo = SystemInfo {
    name: "double",
    description: "double pendulum, Lagrangian (th1, th2, w1, w2) and Hamiltonian (th1, th2, p1, p2) forms (paper §6)",
    parameters: &[
        Quantity {
            name: "m1",
            unit: "kg",
            default: 1.0,
            domain: Domain::Positive,
            description: "mass of the first bob",
        },
        Quantity {
            name: "m2",
            unit: "kg",
            default: 1.0,
            domain: Domain::Positive,
            description: "mass of the second bob",
        },
        Quantity {
            name: "l1",
            unit: "m",
            default: 1.0,
            domain: Domain::Positive,
            description: "length of the first rod",
        },
        Quantity {
            name: "l2",
            unit: "m",
            default: 1.0,
            domain: Domain::Positive,
            description: "length of the second rod",
        },
        Quantity {
            name: "g",
            unit: "m/s^2",
            default: 9.81,
            domain: Domain::Positive,
            description: "gravitational acceleration",
        },
        Quantity {
            name: "damping",
            unit: "N m s",
            default: 0.0,
            domain: Domain::NonNegative,
            description: "viscous friction b at both joints: torques -b w1 (pivot), -b (w2 - w1) (elbow)",
        },
        Quantity {
            name: "drive_amplitude",
            unit: "N m",
            default: 0.0,
            domain: Domain::Real,
            description: "amplitude A of the driving torque A cos(W t) on the first rod",
        },
        Quantity {
            name: "drive_frequency",
            unit: "rad/s",
            default: 0.0,
            domain: Domain::NonNegative,
            description: "angular frequency W of the drive",
        },
    ],
    state: &[
        Quantity {
            name: "theta1",
            unit: "rad",
            default: 120.0 * PI / 180.0,
            domain: Domain::Real,
            description: "angle of the first rod from the downward vertical",
        },
        Quantity {
            name: "theta2",
            unit: "rad",
            default: -10.0 * PI / 180.0,
            domain: Domain::Real,
            description: "angle of the second rod from the downward vertical",
        },
        Quantity {
            name: "omega1",
            unit: "rad/s",
            default: 0.0,
            domain: Domain::Real,
            description: "angular velocity of the first rod",
        },
        Quantity {
            name: "omega2",
            unit: "rad/s",
            default: 0.0,
            domain: Domain::Real,
            description: "angular velocity of the second rod",
        },
    ],
    variant: None,
    dimensionless: false,
    study_periods: 1.0,
    energy_scale: "(m1 + m2) g l1 + m2 g l2, the potential energy gained from hanging at rest to both rods horizontal, or E(0) - V_min if larger",
};

/// The terms of the matrix formalism M(θ) θ'' + C + G = 0 (paper (73)–(75), with C the
/// whole velocity vector as (74) defines it; see ERRATA on (70)/(71)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatrixForm {
    /// Mass matrix M (73), kg m².
    pub mass: [[f64; 2]; 2],
    /// Velocity (Coriolis and centripetal) vector C (74), N m.
    pub coriolis: [f64; 2],
    /// Gravity vector G (75), N m.
    pub gravity: [f64; 2],
}

impl DoublePendulum {
    /// M, C and G at state y (paper (73)–(75)).
    pub fn matrix_form(&self, y: &[f64]) -> MatrixForm {
        let Self { m1, m2, l1, l2, g, .. } = *self;
        let (s, c) = (y[0] - y[1]).sin_cos();
        let b = m2 * l1 * l2;
        MatrixForm {
            mass: [[l1 * l1 * (m1 + m2), b * c], [b * c, m2 * l2 * l2]],
            coriolis: [b * y[3] * y[3] * s, -b * y[2] * y[2] * s],
            gravity: [g * l1 * (m1 + m2) * y[0].sin(), m2 * g * l2 * y[1].sin()],
        }
    }

    /// Generalized momenta p = M(θ) ω (paper (84) with the ERRATA's [θ̇₁, θ̇₂]), kg m²/s.
    pub fn momenta(&self, y: &[f64]) -> [f64; 2] {
        let Self { m1, m2, l1, l2, .. } = *self;
        let c = (y[0] - y[1]).cos();
        [(m1 + m2) * l1 * l1 * y[2] + m2 * l1 * l2 * c * y[3], m2 * l2 * l2 * y[3] + m2 * l1 * l2 * c * y[2]]
    }

    /// Kinetic energy T (43), J.
    pub fn kinetic(&self, y: &[f64]) -> f64 {
        self.kinetic_from(y[2], y[3], (y[0] - y[1]).cos())
    }

    /// Potential energy V (46), J; zero when both rods are horizontal at the pivot's height.
    pub fn potential(&self, theta1: f64, theta2: f64) -> f64 {
        self.potential_from(theta1.cos(), theta2.cos())
    }

    /// Lagrangian L = T − V (47), J.
    pub fn lagrangian(&self, y: &[f64]) -> f64 {
        self.kinetic(y) - self.potential(y[0], y[1])
    }

    /// The Hamiltonian form with the same parameters.
    pub fn form(&self) -> DoublePendulumForm {
        DoublePendulumForm { pendulum: *self }
    }

    /// `N` pendulums as one whose parameters are arrays (lane i the i-th pendulum's), for a
    /// lane group of the ensemble engine.
    pub fn transpose<const N: usize>(all: [Self; N]) -> DoublePendulum<[f64; N]> {
        DoublePendulum {
            m1: all.map(|d| d.m1),
            m2: all.map(|d| d.m2),
            l1: all.map(|d| d.l1),
            l2: all.map(|d| d.l2),
            g: all.map(|d| d.g),
            damping: all.map(|d| d.damping),
            drive_amplitude: all.map(|d| d.drive_amplitude),
            drive_frequency: all.map(|d| d.drive_frequency),
        }
    }

    /// The parameters as dual numbers (constants), for Jacobians.
    fn dual(&self) -> DoublePendulum<Dual64> {
        self.map(Dual64::from)
    }
}

impl<T: Copy> DoublePendulum<T> {
    /// The same pendulum with each parameter converted by `f` (to lanes, to dual numbers).
    pub fn map<U>(&self, f: impl Fn(T) -> U) -> DoublePendulum<U> {
        DoublePendulum {
            m1: f(self.m1),
            m2: f(self.m2),
            l1: f(self.l1),
            l2: f(self.l2),
            g: f(self.g),
            damping: f(self.damping),
            drive_amplitude: f(self.drive_amplitude),
            drive_frequency: f(self.drive_frequency),
        }
    }
}

/// The equations, written once over every number type.
impl<T: Num> DoublePendulum<T> {
    /// Whether damping or a drive acts (in some lane): then the energy is not conserved, and
    /// the forces' terms are computed.
    #[inline(always)]
    pub fn is_forced(&self) -> bool {
        !(self.damping.is_zero() && self.drive_amplitude.is_zero())
    }

    /// The driving torque A cos(Ω t) on the first rod, N m.
    #[inline(always)]
    pub fn drive(&self, t: T) -> T {
        if self.drive_amplitude.is_zero() {
            T::splat(0.0)
        } else {
            self.drive_amplitude * (self.drive_frequency * t).cos()
        }
    }

    /// The generalized forces (Q₁, Q₂) of the joint friction and the drive at time t, N m:
    /// Q₁ = −b ω₁ + b (ω₂ − ω₁) + A cos(Ω t), Q₂ = −b (ω₂ − ω₁). They enter the right-hand
    /// side of the Euler–Lagrange equations, M θ'' + C + G = Q.
    #[inline(always)]
    pub fn generalized_forces(&self, t: T, w1: T, w2: T) -> [T; 2] {
        let b = self.damping;
        [b * (w2 - T::splat(2.0) * w1) + self.drive(t), -b * (w2 - w1)]
    }

    /// The angular accelerations (θ₁'', θ₂'') at (t, y), y = (θ₁, θ₂, ω₁, ω₂): θ'' = M⁻¹ (Q −
    /// C − G) (paper (76), (81), (82)); see [`DoublePendulum::accelerations_from`].
    #[inline(always)]
    pub fn accelerations(&self, t: T, y: &[T; 4]) -> [T; 2] {
        let (sd, cd) = (y[0] - y[1]).sin_cos();
        self.accelerations_from(t, y, [sd, cd, y[0].sin(), y[1].sin()])
    }

    /// [`DoublePendulum::accelerations`] from `trig` = (sin(θ₁ − θ₂), cos(θ₁ − θ₂), sin θ₁,
    /// sin θ₂), the first row of the matrix equation divided by l₁ and the second by m₂ l₂. In
    /// the reference arithmetic (`f64`) the expressions are, in order, those
    /// `shared/bench/SPEC.md` fixes, so that the result is bit-identical to the benchmark's C
    /// peers; the engine's ([`crate::num::Lanes`]) fuses the products and sums marked `madd`
    /// where the CPU can, and divides once.
    #[inline(always)]
    pub fn accelerations_from(&self, t: T, y: &[T; 4], trig: [T; 4]) -> [T; 2] {
        let Self { m1, m2, l1, l2, g, .. } = *self;
        let [sd, cd, s1, s2] = trig;
        let (w1, w2) = (y[2], y[3]);
        let m11 = (m1 + m2) * l1;
        let m12 = m2 * l2 * cd;
        let m21 = l1 * cd;
        let m22 = l2;
        let mut r1 = (-m2 * l2 * w2 * w2).madd(sd, -((m1 + m2) * g * s1));
        let mut r2 = (l1 * w1 * w1).madd(sd, -(g * s2));
        // Tested, not assumed zero: the free pendulum's expressions stay the spec's, and the
        // forces cost it one test.
        if self.is_forced() {
            (r1, r2) = self.add_forces(t, w1, w2, r1, r2);
        }
        let det = m11.madd(m22, -(m12 * m21));
        let (a1, a2) = T::div2(r1.madd(m22, -(m12 * r2)), m11.madd(r2, -(m21 * r1)), det);
        [a1, a2]
    }

    /// The rows of [`DoublePendulum::accelerations_from`] with the generalized forces added
    /// (Q₁ / l₁, Q₂ / (m₂ l₂)); out of line, so that they cost the free pendulum nothing.
    #[inline(always)]
    fn add_forces(&self, t: T, w1: T, w2: T, r1: T, r2: T) -> (T, T) {
        let [q1, q2] = self.generalized_forces(t, w1, w2);
        (r1 + q1 / self.l1, r2 + q2 / (self.m2 * self.l2))
    }

    /// Kinetic energy T (43) from ω₁, ω₂ and cos(θ₁ − θ₂), J.
    #[inline(always)]
    pub fn kinetic_from(&self, w1: T, w2: T, cd: T) -> T {
        let Self { m1, m2, l1, l2, .. } = *self;
        let half = T::splat(0.5);
        half * (m1 + m2) * l1 * l1 * w1 * w1 + half * m2 * l2 * l2 * w2 * w2 + m2 * l1 * l2 * w1 * w2 * cd
    }

    /// Potential energy V (46) from cos θ₁ and cos θ₂, J.
    #[inline(always)]
    pub fn potential_from(&self, c1: T, c2: T) -> T {
        let Self { m1, m2, l1, l2, g, .. } = *self;
        -(m1 + m2) * g * l1 * c1 - m2 * g * l2 * c2
    }

    /// The energy T + V at y from (cos(θ₁ − θ₂), cos θ₁, cos θ₂), J.
    #[inline(always)]
    pub fn energy_from(&self, y: &[T; 4], [cd, c1, c2]: [T; 3]) -> T {
        self.kinetic_from(y[2], y[3], cd) + self.potential_from(c1, c2)
    }

    /// The gradient (∂H/∂θ₁, ∂H/∂θ₂, ∂H/∂p₁, ∂H/∂p₂) of the Hamiltonian (94) at (t, q, p):
    /// ∂H/∂θ = −ṗ from (108), (109), with the drive's −θ₁ A cos(Ω t) (the form exists only
    /// without damping), and ∂H/∂p = θ̇ from (87), (88).
    #[inline(always)]
    pub fn hamiltonian_gradient(&self, t: T, [q1, q2]: [T; 2], [p1, p2]: [T; 2]) -> [T; 4] {
        let Self { m1, m2, l1, l2, g, .. } = *self;
        let (s, c) = (q1 - q2).sin_cos();
        let d = m1 + m2 * s * s;
        let bracket = m2 * c / (l1 * l1) * p1 * p1 - (m2 * c * c + (m1 + m2)) / (l1 * l2) * p1 * p2
            + (m1 + m2) * c / (l2 * l2) * p2 * p2;
        let coupling = s / (d * d) * bracket;
        let mut dq1 = -coupling + (m1 + m2) * g * l1 * q1.sin();
        if !self.drive_amplitude.is_zero() {
            dq1 = dq1 - self.drive(t);
        }
        let dq2 = coupling + m2 * g * l2 * q2.sin();
        let det = m2 * l1 * l1 * l2 * l2 * d;
        let b = m2 * l1 * l2 * c;
        [dq1, dq2, (m2 * l2 * l2 * p1 - b * p2) / det, (-b * p1 + l1 * l1 * (m1 + m2) * p2) / det]
    }
}

/// θ' = ω, θ'' from [`DoublePendulum::accelerations`].
impl<T: Num> Equations<T> for DoublePendulum<T> {
    #[inline(always)]
    fn rhs(&self, t: T, y: &[T], dydt: &mut [T]) {
        let y: &[T; 4] = y.try_into().expect("four state variables");
        let [a1, a2] = self.accelerations(t, y);
        dydt.copy_from_slice(&[y[2], y[3], a1, a2]);
    }

    /// 2 max |θᵢ| (the angles and their difference), and the drive's phase Ω t.
    #[inline(always)]
    fn trig_reach(&self, t: T, y: &[T]) -> T {
        let angles = super::reach(&y[..2]);
        if self.drive_amplitude.is_zero() { angles } else { angles.max((self.drive_frequency * t).abs()) }
    }
}

/// [`DoublePendulum::hamiltonian_gradient`].
impl<T: Num> super::Canonical<T> for DoublePendulum<T> {
    #[inline(always)]
    fn gradient(&self, t: T, q: &[T], p: &[T], dq: &mut [T], dp: &mut [T]) {
        let [g1, g2, w1, w2] = self.hamiltonian_gradient(t, [q[0], q[1]], [p[0], p[1]]);
        dq[..2].copy_from_slice(&[g1, g2]);
        dp[..2].copy_from_slice(&[w1, w2]);
    }
}

impl Model for DoublePendulum {
    type Form = DoublePendulumForm;
    const INFO: &'static SystemInfo = &INFO;
    const DIM: usize = 4;
    type Over<T: Num> = DoublePendulum<T>;

    fn convert<T: Num>(&self, f: &dyn Fn(f64) -> T) -> DoublePendulum<T> {
        self.map(f)
    }

    fn over<T: Num>(_: &dyn Fn(&str) -> f64, v: &dyn Fn(&str) -> T) -> DoublePendulum<T> {
        DoublePendulum {
            m1: v("m1"),
            m2: v("m2"),
            l1: v("l1"),
            l2: v("l2"),
            g: v("g"),
            damping: v("damping"),
            drive_amplitude: v("drive_amplitude"),
            drive_frequency: v("drive_frequency"),
        }
    }

    fn autonomous(&self) -> bool {
        self.drive_amplitude == 0.0
    }

    fn from_values(v: &Values) -> Self {
        Self::over(&|n| v.get(n), &|n| v.get(n))
    }

    fn hamiltonian_form(&self) -> Result<DoublePendulumForm, String> {
        if self.damping != 0.0 {
            return Err(format!("the double pendulum with damping = {} is not Hamiltonian", self.damping));
        }
        Ok(self.form())
    }

    fn to_momenta(&self, y: &[f64], z: &mut [f64]) {
        let p = self.momenta(y);
        z[..2].copy_from_slice(&y[..2]);
        z[2..4].copy_from_slice(&p);
    }

    fn to_velocities(&self, z: &[f64], y: &mut [f64]) {
        let mut w = [0.0; 2];
        self.form().dh_dp(0.0, &z[..2], &z[2..4], &mut w);
        y[..2].copy_from_slice(&z[..2]);
        y[2..4].copy_from_slice(&w);
    }

    /// 2π √(max(l₁, l₂)/g): the longer rod's pendulum period.
    fn time_scale(&self) -> f64 {
        std::f64::consts::TAU * (self.l1.max(self.l2) / self.g).sqrt()
    }

    fn energy_scale(&self, y0: &[f64]) -> f64 {
        let Self { m1, m2, l1, l2, g, .. } = *self;
        let above_min = Energy::energy(self, 0.0, y0) - self.potential(0.0, 0.0);
        ((m1 + m2) * g * l1 + m2 * g * l2).max(above_min)
    }

    /// Q · ω, the power of the joint friction and the drive.
    fn power(&self, t: f64, y: &[f64]) -> f64 {
        let [q1, q2] = self.generalized_forces(t, y[2], y[3]);
        q1 * y[2] + q2 * y[3]
    }
}

impl System for DoublePendulum {
    fn dim(&self) -> usize {
        4
    }

    /// θ' = ω and θ'' from [`DoublePendulum::accelerations`] (bit-identical to the benchmark
    /// peers' C reference).
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        Equations::rhs(self, t, y, dydt);
    }

    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) -> bool {
        let dual = self.dual();
        dual_jacobian(
            4,
            |y, out| {
                let y = [y[0], y[1], y[2], y[3]];
                let [a1, a2] = dual.accelerations(Dual64::from(t), &y);
                out.copy_from_slice(&[y[2], y[3], a1, a2]);
            },
            y,
            jac,
        );
        true
    }
}

impl Energy for DoublePendulum {
    fn energy(&self, _t: f64, y: &[f64]) -> f64 {
        self.kinetic(y) + self.potential(y[0], y[1])
    }
}

/// The double pendulum on (θ₁, θ₂, p₁, p₂) (paper §6.5–6.8); H = T(θ, p) + V(θ) (94) is not
/// separable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DoublePendulumForm {
    /// The parameters.
    pub pendulum: DoublePendulum,
}

impl System for DoublePendulumForm {
    fn dim(&self) -> usize {
        4
    }
    /// Hamilton's equations (∂H/∂p, −∂H/∂q), the gradient computed once.
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        let [dq1, dq2, dp1, dp2] = self.pendulum.hamiltonian_gradient(t, [y[0], y[1]], [y[2], y[3]]);
        dydt.copy_from_slice(&[dp1, dp2, -dq1, -dq2]);
    }

    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) -> bool {
        let dual = self.pendulum.dual();
        dual_jacobian(
            4,
            |y, out| {
                let [dq1, dq2, dp1, dp2] =
                    dual.hamiltonian_gradient(Dual64::from(t), [y[0], y[1]], [y[2], y[3]]);
                out.copy_from_slice(&[dp1, dp2, -dq1, -dq2]);
            },
            y,
            jac,
        );
        true
    }
}

impl Hamiltonian for DoublePendulumForm {
    /// ∂H/∂θ = −ṗ from (108) and (109) ([`DoublePendulum::hamiltonian_gradient`]).
    fn dh_dq(&self, t: f64, q: &[f64], p: &[f64], out: &mut [f64]) {
        let g = self.pendulum.hamiltonian_gradient(t, [q[0], q[1]], [p[0], p[1]]);
        out.copy_from_slice(&g[..2]);
    }

    /// ∂H/∂p = θ̇ from (87) and (88) ([`DoublePendulum::hamiltonian_gradient`]).
    fn dh_dp(&self, t: f64, q: &[f64], p: &[f64], out: &mut [f64]) {
        let g = self.pendulum.hamiltonian_gradient(t, [q[0], q[1]], [p[0], p[1]]);
        out.copy_from_slice(&g[2..]);
    }
}

impl Energy for DoublePendulumForm {
    /// H = ½ pᵀ M⁻¹ p + V (92)–(94), J.
    fn energy(&self, t: f64, y: &[f64]) -> f64 {
        let mut w = [0.0; 2];
        self.dh_dp(t, &y[..2], &y[2..4], &mut w);
        0.5 * (y[2] * w[0] + y[3] * w[1]) + self.pendulum.potential(y[0], y[1])
    }
}
