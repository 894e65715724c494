//! The planar double pendulum: the paper's §6, Lagrangian form (matrix formalism (73)–(82))
//! and Hamiltonian form ((87), (88), (108), (109)).

use std::f64::consts::PI;

use num_dual::DualNum;

use super::{Domain, Energy, Hamiltonian, Model, Quantity, System, SystemInfo, Values, dual_jacobian};

/// Two point masses on massless rigid rods, the second hung from the first.
///
/// State y = (θ₁, θ₂, ω₁, ω₂): angles from the downward vertical (rad) and angular
/// velocities (rad/s). Its Hamiltonian (94) is not separable (the mass matrix depends on
/// θ₁ − θ₂), so explicit splitting methods do not apply: symplectic methods run on
/// [`DoublePendulumForm`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DoublePendulum {
    /// Mass of the first bob m₁, kg.
    pub m1: f64,
    /// Mass of the second bob m₂, kg.
    pub m2: f64,
    /// Length of the first rod l₁, m.
    pub l1: f64,
    /// Length of the second rod l₂, m.
    pub l2: f64,
    /// Gravitational acceleration g, m/s².
    pub g: f64,
    /// Viscous friction coefficient b at both joints, N m s/rad: torques −b θ̇₁ at the pivot
    /// and −b (θ̇₂ − θ̇₁) at the elbow (on the second rod; its reaction on the first).
    pub damping: f64,
    /// Amplitude A of the driving torque A cos(Ω t) on the first rod, N m.
    pub drive_amplitude: f64,
    /// Angular frequency Ω of the drive, rad/s.
    pub drive_frequency: f64,
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
    build: |v| Box::new(DoublePendulum::from_values(v)),
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

    /// Whether damping or a drive acts (then the energy is not conserved, and the ensemble
    /// engine's kernels, which implement the free equations, do not apply).
    pub fn is_forced(&self) -> bool {
        self.damping != 0.0 || self.drive_amplitude != 0.0
    }

    /// The generalized forces (Q₁, Q₂) of the joint friction and the drive at time t, N m:
    /// Q₁ = −b ω₁ + b (ω₂ − ω₁) + A cos(Ω t), Q₂ = −b (ω₂ − ω₁). They enter the right-hand
    /// side of the Euler–Lagrange equations, M θ'' + C + G = Q.
    pub fn generalized_forces(&self, t: f64, w1: f64, w2: f64) -> [f64; 2] {
        let b = self.damping;
        [b * (w2 - 2.0 * w1) + self.drive(t), -b * (w2 - w1)]
    }

    /// The rows of the Lagrangian right-hand side with the generalized forces added (first
    /// row divided by l₁, second by m₂ l₂, as in [`System::rhs`]).
    #[cold]
    #[inline(never)]
    fn add_forces(&self, t: f64, w1: f64, w2: f64, r1: f64, r2: f64) -> (f64, f64) {
        let [q1, q2] = self.generalized_forces(t, w1, w2);
        (r1 + q1 / self.l1, r2 + q2 / (self.m2 * self.l2))
    }

    /// The driving torque A cos(Ω t) on the first rod, N m.
    pub fn drive(&self, t: f64) -> f64 {
        if self.drive_amplitude == 0.0 {
            0.0
        } else {
            self.drive_amplitude * (self.drive_frequency * t).cos()
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
        let Self { m1, m2, l1, l2, .. } = *self;
        let (w1, w2) = (y[2], y[3]);
        0.5 * (m1 + m2) * l1 * l1 * w1 * w1
            + 0.5 * m2 * l2 * l2 * w2 * w2
            + m2 * l1 * l2 * w1 * w2 * cos(y[0] - y[1])
    }

    /// Potential energy V (46), J; zero when both rods are horizontal at the pivot's height.
    pub fn potential(&self, theta1: f64, theta2: f64) -> f64 {
        let Self { m1, m2, l1, l2, g, .. } = *self;
        -(m1 + m2) * g * l1 * cos(theta1) - m2 * g * l2 * cos(theta2)
    }

    /// Lagrangian L = T − V (47), J.
    pub fn lagrangian(&self, y: &[f64]) -> f64 {
        self.kinetic(y) - self.potential(y[0], y[1])
    }

    /// The Hamiltonian form with the same parameters.
    pub fn form(&self) -> DoublePendulumForm {
        DoublePendulumForm { pendulum: *self }
    }

    /// The Lagrangian right-hand side (the expressions of [`System::rhs`]) over any number
    /// type, for its Jacobian by forward-mode automatic differentiation (num-dual).
    fn rhs_generic<T: DualNum<Primitive = f64> + Copy>(&self, t: f64, y: [T; 4]) -> [T; 4] {
        let Self { m1, m2, l1, l2, g, .. } = *self;
        let [th1, th2, w1, w2] = y;
        let (sd, cd) = (th1 - th2).sin_cos();
        let (m11, m22) = (T::from((m1 + m2) * l1), T::from(l2));
        let (m12, m21) = (cd * (m2 * l2), cd * l1);
        // The forces enter before M⁻¹, which depends on θ: both stay in the Jacobian.
        let b = self.damping;
        let r1 = w2 * w2 * sd * (-m2 * l2) - th1.sin() * ((m1 + m2) * g)
            + (w2 * b - w1 * (2.0 * b) + self.drive(t)) / l1;
        let r2 = w1 * w1 * sd * l1 - th2.sin() * g - (w2 - w1) * b / (m2 * l2);
        let det = m11 * m22 - m12 * m21;
        [w1, w2, (r1 * m22 - m12 * r2) / det, (m11 * r2 - m21 * r1) / det]
    }
}

/// The cosine the energy uses: the engine's ([`crate::ensemble::trig`]: within 2 ulp of
/// libm's, or 6.8·10⁻²¹ near the multiples of π/2, for every angle), which costs a third of
/// libm's where the energy is tracked at every step (`pendula simulate`).
#[inline]
fn cos(x: f64) -> f64 {
    crate::ensemble::trig::sin_cos(x).1
}

impl Model for DoublePendulum {
    type Form = DoublePendulumForm;
    const INFO: &'static SystemInfo = &INFO;

    fn autonomous(&self) -> bool {
        self.drive_amplitude == 0.0
    }

    fn from_values(v: &Values) -> Self {
        DoublePendulum {
            m1: v.get("m1"),
            m2: v.get("m2"),
            l1: v.get("l1"),
            l2: v.get("l2"),
            g: v.get("g"),
            damping: v.get("damping"),
            drive_amplitude: v.get("drive_amplitude"),
            drive_frequency: v.get("drive_frequency"),
        }
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

    /// θ'' = −M⁻¹ (C + G) (paper (76), (81), (82)), with the first row of the matrix
    /// equation divided by l₁ and the second by m₂ l₂. The expression order is the one
    /// `shared/bench/SPEC.md` fixes, so that without FMA the result is bit-identical to the
    /// benchmark peers.
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        let Self { m1, m2, l1, l2, g, .. } = *self;
        let (th1, th2, w1, w2) = (y[0], y[1], y[2], y[3]);
        let d = th1 - th2;
        let (sd, cd) = (d.sin(), d.cos());
        let (s1, s2) = (th1.sin(), th2.sin());
        let m11 = (m1 + m2) * l1;
        let m12 = m2 * l2 * cd;
        let m21 = l1 * cd;
        let m22 = l2;
        let mut r1 = -m2 * l2 * w2 * w2 * sd - (m1 + m2) * g * s1;
        let mut r2 = l1 * w1 * w1 * sd - g * s2;
        // Tested, not assumed zero: the unforced expressions stay bit-identical to the spec's,
        // and the forced terms stay out of line so that they cost the free pendulum nothing.
        if self.is_forced() {
            (r1, r2) = self.add_forces(t, w1, w2, r1, r2);
        }
        let det = m11 * m22 - m12 * m21;
        dydt[0] = w1;
        dydt[1] = w2;
        dydt[2] = (r1 * m22 - m12 * r2) / det;
        dydt[3] = (m11 * r2 - m21 * r1) / det;
    }

    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) -> bool {
        dual_jacobian(
            4,
            |y, out| out.copy_from_slice(&self.rhs_generic(t, [y[0], y[1], y[2], y[3]])),
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
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        super::hamilton_rhs(self, t, y, dydt);
    }

    fn jacobian(&self, _t: f64, y: &[f64], jac: &mut [f64]) -> bool {
        dual_jacobian(4, |y, out| out.copy_from_slice(&self.rhs_generic([y[0], y[1], y[2], y[3]])), y, jac);
        true
    }
}

impl DoublePendulumForm {
    /// Hamilton's equations (∂H/∂p, −∂H/∂q) with the expressions of [`Hamiltonian::dh_dq`]
    /// and [`Hamiltonian::dh_dp`], over any number type (for the Jacobian).
    fn rhs_generic<T: DualNum<Primitive = f64> + Copy>(&self, y: [T; 4]) -> [T; 4] {
        let DoublePendulum { m1, m2, l1, l2, g, .. } = self.pendulum;
        let [q1, q2, p1, p2] = y;
        let (s, c) = (q1 - q2).sin_cos();
        let d = s * s * m2 + m1;
        let bracket = c * (m2 / (l1 * l1)) * p1 * p1 - (c * c * m2 + (m1 + m2)) / (l1 * l2) * p1 * p2
            + c * ((m1 + m2) / (l2 * l2)) * p2 * p2;
        let coupling = s / (d * d) * bracket;
        let det = (s * s * m2 + m1) * (m2 * l1 * l1 * l2 * l2);
        let b = c * (m2 * l1 * l2);
        [
            (p1 * (m2 * l2 * l2) - b * p2) / det,
            (-b * p1 + p2 * (l1 * l1 * (m1 + m2))) / det,
            coupling - q1.sin() * ((m1 + m2) * g * l1),
            -coupling - q2.sin() * (m2 * g * l2),
        ]
    }
}

impl Hamiltonian for DoublePendulumForm {
    /// ∂H/∂θ = −ṗ from (108) and (109).
    fn dh_dq(&self, t: f64, q: &[f64], p: &[f64], out: &mut [f64]) {
        let DoublePendulum { m1, m2, l1, l2, g, .. } = self.pendulum;
        let (s, c) = (q[0] - q[1]).sin_cos();
        let d = m1 + m2 * s * s;
        let (p1, p2) = (p[0], p[1]);
        let bracket = m2 * c / (l1 * l1) * p1 * p1 - (m2 * c * c + (m1 + m2)) / (l1 * l2) * p1 * p2
            + (m1 + m2) * c / (l2 * l2) * p2 * p2;
        let coupling = s / (d * d) * bracket;
        // A drive adds −θ₁ A cos(Ω t) to H (the form exists only without damping).
        out[0] = -coupling + (m1 + m2) * g * l1 * q[0].sin() - self.pendulum.drive(t);
        out[1] = coupling + m2 * g * l2 * q[1].sin();
    }

    /// ∂H/∂p = θ̇ from (87) and (88).
    fn dh_dp(&self, _t: f64, q: &[f64], p: &[f64], out: &mut [f64]) {
        let DoublePendulum { m1, m2, l1, l2, .. } = self.pendulum;
        let (s, c) = (q[0] - q[1]).sin_cos();
        let det = m2 * l1 * l1 * l2 * l2 * (m1 + m2 * s * s);
        let b = m2 * l1 * l2 * c;
        out[0] = (m2 * l2 * l2 * p[0] - b * p[1]) / det;
        out[1] = (-b * p[0] + l1 * l1 * (m1 + m2) * p[1]) / det;
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
