//! The planar N-link pendulum (a chain of point masses on massless rods) in the
//! mass-matrix formalism M(θ) θ'' = f(θ, θ'), the paper's §6 matrix form generalised to N
//! links, with its Hamiltonian form on (θ, p = M ω).
//!
//! With μₖ = Σ_{i ≥ k} mᵢ (the mass hanging from joint k) and μᵢⱼ = μ_max(i,j):
//! Mᵢⱼ = μᵢⱼ lᵢ lⱼ cos(θᵢ − θⱼ),
//! fᵢ = −Σⱼ μᵢⱼ lᵢ lⱼ sin(θᵢ − θⱼ) ωⱼ² − μᵢ g lᵢ sin θᵢ,
//! V = −Σₖ μₖ g lₖ cos θₖ, T = ½ ωᵀ M ω, and
//! ∂H/∂θₖ = Σⱼ μₖⱼ lₖ lⱼ ωₖ ωⱼ sin(θₖ − θⱼ) + μₖ g lₖ sin θₖ with ω = M⁻¹ p.
//! N = 1 is [`super::pendulum`] and N = 2 is [`super::double`] (checked by tests to
//! round-off).

use std::f64::consts::PI;

use num_dual::Dual64;

use super::{
    Domain, Energy, Equations, Hamiltonian, Model, Quantity, System, SystemInfo, Values, dual_jacobian,
};
use crate::Error;
use crate::num::Num;

/// The most links a chain may have: its matrices live on the stack, sized for it.
pub const MAX_LINKS: usize = 8;

/// A planar chain of `n` point masses on massless rigid rods, hung from a fixed pivot.
///
/// State y = (θ₁…θₙ, ω₁…ωₙ): angles from the downward vertical (rad) and angular
/// velocities (rad/s). Its Hamiltonian is not separable (for n ≥ 2): symplectic methods
/// run on [`ChainForm`] (implicit Gauss–Legendre).
///
/// The parameters are of any [`Num`] type (its equations are written once, [`Equations`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chain<T = f64> {
    /// Number of links n, 1 to [`MAX_LINKS`].
    pub n: usize,
    /// Masses m₁…mₙ, kg (entries past n unused).
    pub m: [T; MAX_LINKS],
    /// Rod lengths l₁…lₙ, m (entries past n unused).
    pub l: [T; MAX_LINKS],
    /// Gravitational acceleration g, m/s².
    pub g: T,
}

macro_rules! link {
    ($m:literal, $l:literal) => {
        [
            Quantity {
                name: $m,
                unit: "kg",
                default: 1.0,
                domain: Domain::Positive,
                description: "mass of this link's bob",
            },
            Quantity {
                name: $l,
                unit: "m",
                default: 1.0,
                domain: Domain::Positive,
                description: "length of this link's rod",
            },
        ]
    };
}

const fn flatten<const N: usize, const M: usize>(
    head: [Quantity; 2],
    links: [[Quantity; 2]; N],
) -> [Quantity; M] {
    let mut out = [head[0]; M];
    out[1] = head[1];
    let mut i = 0;
    while i < N {
        out[2 + 2 * i] = links[i][0];
        out[3 + 2 * i] = links[i][1];
        i += 1;
    }
    out
}

/// links, g, then (mₖ, lₖ) per link: the first 2 + 2n are the parameters of an n-link chain.
static PARAMETERS: [Quantity; 2 + 2 * MAX_LINKS] = flatten(
    [
        Quantity {
            name: "links",
            unit: "1",
            default: 3.0,
            domain: Domain::Links,
            description: "number of links N (1 to 8)",
        },
        Quantity {
            name: "g",
            unit: "m/s^2",
            default: 9.81,
            domain: Domain::Positive,
            description: "gravitational acceleration",
        },
    ],
    [
        link!("m1", "l1"),
        link!("m2", "l2"),
        link!("m3", "l3"),
        link!("m4", "l4"),
        link!("m5", "l5"),
        link!("m6", "l6"),
        link!("m7", "l7"),
        link!("m8", "l8"),
    ],
);

const THETA: [&str; MAX_LINKS] =
    ["theta1", "theta2", "theta3", "theta4", "theta5", "theta6", "theta7", "theta8"];
const OMEGA: [&str; MAX_LINKS] =
    ["omega1", "omega2", "omega3", "omega4", "omega5", "omega6", "omega7", "omega8"];

/// The state quantities of an n-link chain, (θ₁…θₙ, ω₁…ωₙ), in the first 2n entries (the
/// rest repeat the last and are never shown): θ₁ = 120°, θ₂ = −10° (the double pendulum's
/// defaults), the other angles 0, at rest.
const fn states(n: usize) -> [Quantity; 2 * MAX_LINKS] {
    let mut out =
        [Quantity { name: "", unit: "", default: 0.0, domain: Domain::Real, description: "" }; 2 * MAX_LINKS];
    let mut k = 0;
    while k < MAX_LINKS {
        let default = match k {
            0 => 120.0 * PI / 180.0,
            1 => -10.0 * PI / 180.0,
            _ => 0.0,
        };
        let angle = Quantity {
            name: THETA[k],
            unit: "rad",
            default,
            domain: Domain::Real,
            description: "angle of this rod from the downward vertical",
        };
        let rate = Quantity {
            name: OMEGA[k],
            unit: "rad/s",
            default: 0.0,
            domain: Domain::Real,
            description: "angular velocity of this rod",
        };
        if k < n {
            out[k] = angle;
            out[n + k] = rate;
        }
        k += 1;
    }
    out
}

static STATES: [[Quantity; 2 * MAX_LINKS]; MAX_LINKS] =
    [states(1), states(2), states(3), states(4), states(5), states(6), states(7), states(8)];

const fn member_info(n: usize, parameters: &'static [Quantity], states: &'static [Quantity]) -> SystemInfo {
    SystemInfo {
        name: "chain",
        description: "planar N-link pendulum (links = 1..8), mass-matrix form M(th) th'' = f and Hamiltonian form",
        parameters: parameters.split_at(2 + 2 * n).0,
        state: states.split_at(2 * n).0,
        variant: None,
        dimensionless: false,
        study_periods: 0.5,
        energy_scale: "the potential energy gained from hanging at rest to every rod horizontal, sum over k of (m_k + ... + m_N) g l_k, or E(0) - V_min if larger",
    }
}

/// The entries of the chains with 1 to [`MAX_LINKS`] links.
static MEMBERS: [SystemInfo; MAX_LINKS] = [
    member_info(1, &PARAMETERS, &STATES[0]),
    member_info(2, &PARAMETERS, &STATES[1]),
    member_info(3, &PARAMETERS, &STATES[2]),
    member_info(4, &PARAMETERS, &STATES[3]),
    member_info(5, &PARAMETERS, &STATES[4]),
    member_info(6, &PARAMETERS, &STATES[5]),
    member_info(7, &PARAMETERS, &STATES[6]),
    member_info(8, &PARAMETERS, &STATES[7]),
];

/// Catalogue entry of the chain family: it lists the quantities of the largest chain (so
/// names can be checked before `links` is known); the `links` setting (default 3) picks the
/// member whose entry the values use ([`SystemInfo::variant`]).
pub static INFO: SystemInfo =
    SystemInfo { variant: Some(member), ..member_info(MAX_LINKS, &PARAMETERS, &STATES[MAX_LINKS - 1]) };

/// The member of the family that `settings` choose by `links` (the last setting wins).
fn member(settings: &[(String, f64)]) -> Result<&'static SystemInfo, Error> {
    let links = settings.iter().rev().find(|(name, _)| name == "links").map_or(3.0, |(_, v)| *v);
    if !Domain::Links.contains(links) {
        return Err(Error::InvalidValue {
            name: "links".into(),
            value: links,
            allowed: Domain::Links.describe(),
        });
    }
    Ok(&MEMBERS[links as usize - 1])
}

impl<T: Copy> Chain<T> {
    /// The same chain with each parameter converted by `f` (to dual numbers, to lanes).
    pub fn map<U: Copy>(&self, f: impl Fn(T) -> U) -> Chain<U> {
        Chain { n: self.n, m: self.m.map(&f), l: self.l.map(&f), g: f(self.g) }
    }
}

/// The equations, written once over every number type and every capacity `C` ≥ n of the
/// temporaries: [`MAX_LINKS`] for a chain of unknown size, less where the dimension is known
/// when compiling (the ensemble engine's kernels, [`Equations::rhs_sized`]), which spares the
/// zero fill of larger arrays. The arithmetic does not depend on `C` (the same operations in
/// the same order).
impl<T: Num> Chain<T> {
    /// μₖ = Σ_{i ≥ k} mᵢ: the mass below joint k, kg.
    #[inline(always)]
    fn hanging<const C: usize>(&self) -> [T; C] {
        let mut mu = [T::splat(0.0); C];
        let mut sum = T::splat(0.0);
        for k in (0..self.n).rev() {
            sum = sum + self.m[k];
            mu[k] = sum;
        }
        mu
    }

    /// One matrix for what the pairs give: sin(θᵢ − θⱼ) above the diagonal (i < j), the mass
    /// matrix M(θ) (kg m², symmetric) on and below it, which [`solve_spd`] overwrites with
    /// its factors. One `sin_cos` per pair serves the mass matrix and the forces; the pairs
    /// j < i take −sin and cos of the pair (j, i): sin is odd and cos even exactly (in the
    /// platform's trigonometry, the lanes' and the dual numbers' alike), so this is what
    /// evaluating them would give. One n × n temporary, not three: on lanes their zero fill
    /// was most of the overhead.
    #[inline(always)]
    fn pairs<const C: usize>(&self, theta: &[T], mu: &[T; C]) -> [[T; C]; C] {
        let mut a = [[T::splat(0.0); C]; C];
        for i in 0..self.n {
            // cos(θᵢ − θᵢ) = 1 exactly: the diagonal needs no cosine.
            a[i][i] = mu[i] * self.l[i] * self.l[i];
            for j in i + 1..self.n {
                let (s, c) = (theta[i] - theta[j]).sin_cos();
                a[i][j] = s;
                a[j][i] = c * (mu[j] * self.l[j] * self.l[i]);
            }
        }
        a
    }

    /// sin(θᵢ − θⱼ) from [`Chain::pairs`]' matrix.
    #[inline(always)]
    fn sin_of<const C: usize>(a: &[[T; C]; C], i: usize, j: usize) -> T {
        if i < j { a[i][j] } else { -a[j][i] }
    }

    /// θ'' = M⁻¹ f at y = (θ, ω).
    #[inline(always)]
    pub fn accelerations(&self, y: &[T], out: &mut [T]) {
        self.accelerations_in::<MAX_LINKS>(y, out)
    }

    /// [`Chain::accelerations`] with temporaries of capacity `C` ≥ n.
    #[inline(always)]
    fn accelerations_in<const C: usize>(&self, y: &[T], out: &mut [T]) {
        let n = self.n;
        let (theta, omega) = y.split_at(n);
        let mu = self.hanging::<C>();
        let mut a = self.pairs(theta, &mu);
        let mut f = [T::splat(0.0); C];
        for i in 0..n {
            let mut fi = theta[i].sin() * (-mu[i] * self.g * self.l[i]);
            for j in 0..n {
                if j != i {
                    let s = Self::sin_of(&a, i, j);
                    fi = fi - s * omega[j] * omega[j] * (mu[i.max(j)] * self.l[i] * self.l[j]);
                }
            }
            f[i] = fi;
        }
        solve_spd(n, &mut a, &mut f);
        out[..n].copy_from_slice(&f[..n]);
    }

    /// θ' = ω, θ'' = M⁻¹ f with temporaries of capacity `C` ≥ n.
    #[inline(always)]
    fn rhs_in<const C: usize>(&self, y: &[T], dydt: &mut [T]) {
        let n = self.n;
        dydt[..n].copy_from_slice(&y[n..2 * n]);
        self.accelerations_in::<C>(y, &mut dydt[n..]);
    }

    /// ω = M⁻¹ p.
    #[inline(always)]
    fn velocities(&self, theta: &[T], p: &[T], out: &mut [T]) {
        let mut w = [T::splat(0.0); MAX_LINKS];
        self.velocities_in(&mut self.pairs(theta, &self.hanging()), p, &mut w);
        out[..self.n].copy_from_slice(&w[..self.n]);
    }

    /// ω = M⁻¹ p from [`Chain::pairs`]' matrix `a` (left factorised), into `w`.
    #[inline(always)]
    fn velocities_in<const C: usize>(&self, a: &mut [[T; C]; C], p: &[T], w: &mut [T; C]) {
        let n = self.n;
        w[..n].copy_from_slice(&p[..n]);
        solve_spd(n, a, w);
    }

    /// ∂H/∂θ (see the module's formula).
    #[inline(always)]
    fn dh_dtheta(&self, theta: &[T], p: &[T], out: &mut [T]) {
        self.dh_dtheta_and_velocities(theta, p, out, &mut [T::splat(0.0); MAX_LINKS]);
    }

    /// ∂H/∂θ into `out`, and on the way ω = M⁻¹ p (= ∂H/∂p) into `w`.
    #[inline(always)]
    fn dh_dtheta_and_velocities(&self, theta: &[T], p: &[T], out: &mut [T], w: &mut [T; MAX_LINKS]) {
        let n = self.n;
        let mu = self.hanging::<MAX_LINKS>();
        let mut a = self.pairs(theta, &mu);
        self.velocities_in(&mut a, p, w);
        for k in 0..n {
            let mut d = theta[k].sin() * (mu[k] * self.g * self.l[k]);
            for j in 0..n {
                if j != k {
                    let s = Self::sin_of(&a, k, j);
                    d = d + s * w[k] * w[j] * (mu[k.max(j)] * self.l[k] * self.l[j]);
                }
            }
            out[k] = d;
        }
    }
}

impl Chain {
    /// Potential energy V = −Σ μₖ g lₖ cos θₖ, J (zero with every rod horizontal).
    pub fn potential(&self, theta: &[f64]) -> f64 {
        let mu = self.hanging::<MAX_LINKS>();
        (0..self.n).map(|k| -mu[k] * self.g * self.l[k] * theta[k].cos()).sum()
    }

    /// Kinetic energy T = ½ ωᵀ M(θ) ω, J.
    pub fn kinetic(&self, y: &[f64]) -> f64 {
        let (theta, omega) = y.split_at(self.n);
        let mass = self.mass_at(theta);
        let mut t = 0.0;
        for i in 0..self.n {
            for j in 0..self.n {
                t += 0.5 * omega[i] * mass[i][j] * omega[j];
            }
        }
        t
    }

    /// M(θ), kg m².
    #[allow(clippy::needless_range_loop)] // (i, j) and (j, i): the matrix's own notation
    fn mass_at(&self, theta: &[f64]) -> [[f64; MAX_LINKS]; MAX_LINKS] {
        // Above the diagonal, the mirror of what is below (sines there).
        let mut mass = self.pairs(theta, &self.hanging::<MAX_LINKS>());
        for i in 0..self.n {
            for j in i + 1..self.n {
                mass[i][j] = mass[j][i];
            }
        }
        mass
    }

    /// The parameters as dual numbers (constants), for Jacobians.
    fn dual(&self) -> Chain<Dual64> {
        self.map(Dual64::from)
    }
}

/// Solves M x = b in place for a symmetric positive definite n × n M (a mass matrix, read on
/// and below the diagonal of `a`, where its factors are left) by its
/// factorisation M = L D Lᵀ (L unit lower triangular, D diagonal), on the stack: n divisions
/// and no square root, where Cholesky's L Lᵀ takes n square roots and n (n + 3) / 2 divisions
/// (on lanes these dominated the chain's factorisation).
#[allow(clippy::needless_range_loop)] // index loops: the factorisation's own notation
#[inline(always)]
fn solve_spd<T: Num, const C: usize>(n: usize, a: &mut [[T; C]; C], b: &mut [T; C]) {
    // Below the diagonal a becomes L; u holds row j of L D (its first j entries).
    let mut diag = [T::splat(0.0); C];
    let mut inv = [T::splat(0.0); C];
    let mut u = [T::splat(0.0); C];
    for j in 0..n {
        let mut d = a[j][j];
        for k in 0..j {
            u[k] = a[j][k] * diag[k];
            d = d - u[k] * a[j][k];
        }
        diag[j] = d;
        inv[j] = T::splat(1.0) / d;
        for i in j + 1..n {
            let mut s = a[i][j];
            for k in 0..j {
                s = s - a[i][k] * u[k];
            }
            a[i][j] = s * inv[j];
        }
    }
    // L z = b, then Lᵀ x = D⁻¹ z.
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s = s - a[i][k] * b[k];
        }
        b[i] = s;
    }
    for i in (0..n).rev() {
        let mut s = b[i] * inv[i];
        for k in i + 1..n {
            s = s - a[k][i] * b[k];
        }
        b[i] = s;
    }
}

impl Model for Chain {
    type Form = ChainForm;
    const INFO: &'static SystemInfo = &INFO;
    const DIM: usize = 2 * MAX_LINKS;

    type Over<T: Num> = Chain<T>;

    fn convert<T: Num>(&self, f: &dyn Fn(f64) -> T) -> Chain<T> {
        self.map(f)
    }

    fn over<T: Num>(setting: &dyn Fn(&str) -> f64, v: &dyn Fn(&str) -> T) -> Chain<T> {
        const M: [&str; MAX_LINKS] = ["m1", "m2", "m3", "m4", "m5", "m6", "m7", "m8"];
        const L: [&str; MAX_LINKS] = ["l1", "l2", "l3", "l4", "l5", "l6", "l7", "l8"];
        let n = setting("links") as usize;
        // Links past n are unused (zero).
        Chain {
            n,
            m: std::array::from_fn(|k| if k < n { v(M[k]) } else { T::splat(0.0) }),
            l: std::array::from_fn(|k| if k < n { v(L[k]) } else { T::splat(0.0) }),
            g: v("g"),
        }
    }

    fn from_values(v: &Values) -> Self {
        Self::over(&|n| v.get(n), &|n| v.get(n))
    }

    fn info(&self) -> &'static SystemInfo {
        &MEMBERS[self.n - 1]
    }

    fn hamiltonian_form(&self) -> Result<ChainForm, String> {
        Ok(ChainForm { chain: *self })
    }

    fn to_momenta(&self, y: &[f64], z: &mut [f64]) {
        let n = self.n;
        let mass = self.mass_at(&y[..n]);
        z[..n].copy_from_slice(&y[..n]);
        for i in 0..n {
            z[n + i] = (0..n).map(|j| mass[i][j] * y[n + j]).sum();
        }
    }

    fn to_velocities(&self, z: &[f64], y: &mut [f64]) {
        let n = self.n;
        y[..n].copy_from_slice(&z[..n]);
        self.velocities(&z[..n], &z[n..], &mut y[n..]);
    }

    /// 2π √(L/g) with L the chain's total length: the slowest mode's period, within a
    /// factor of order one.
    fn time_scale(&self) -> f64 {
        std::f64::consts::TAU * (self.l[..self.n].iter().sum::<f64>() / self.g).sqrt()
    }

    fn energy_scale(&self, y0: &[f64]) -> f64 {
        let above_min = Energy::energy(self, 0.0, y0) - self.potential(&[0.0; MAX_LINKS][..self.n]);
        self.well_depth().max(above_min)
    }
}

/// ∂H/∂θ and ω = M⁻¹ p (the module's formulas), from one factorisation of M(θ).
impl<T: Num> super::Canonical<T> for Chain<T> {
    #[inline(always)]
    fn gradient(&self, _t: T, q: &[T], p: &[T], dq: &mut [T], dp: &mut [T]) {
        let mut w = [T::splat(0.0); MAX_LINKS];
        self.dh_dtheta_and_velocities(q, p, dq, &mut w);
        dp[..self.n].copy_from_slice(&w[..self.n]);
    }
}

/// θ' = ω, θ'' = M⁻¹ f.
impl<T: Num> Equations<T> for Chain<T> {
    #[inline(always)]
    fn rhs(&self, _t: T, y: &[T], dydt: &mut [T]) {
        self.rhs_in::<MAX_LINKS>(y, dydt);
    }

    /// Temporaries of capacity D/2 (the padded state holds D/2 links at most): 2, 4 or
    /// [`MAX_LINKS`]. The engine compiles a kernel per padded dimension (4, 8 or 16), so
    /// each kernel holds one capacity; 8 × 8 temporaries for 3 links were zero filled
    /// (4 KiB each on lanes) at every evaluation, most of the lanes' overhead.
    #[inline(always)]
    fn rhs_sized<const D: usize>(&self, _t: T, y: &[T; D], dydt: &mut [T; D]) {
        if const { D <= 4 } {
            self.rhs_in::<2>(y, dydt);
        } else if const { D <= 8 } {
            self.rhs_in::<4>(y, dydt);
        } else {
            self.rhs_in::<MAX_LINKS>(y, dydt);
        }
    }

    /// 2 max |θₖ|: the angles and their differences.
    #[inline(always)]
    fn trig_reach(&self, _t: T, y: &[T]) -> T {
        super::reach(&y[..self.n])
    }
}

impl System for Chain {
    fn dim(&self) -> usize {
        2 * self.n
    }

    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        Equations::rhs(self, t, y, dydt);
    }

    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) -> bool {
        let dual = self.dual();
        dual_jacobian(2 * self.n, |y, out| Equations::rhs(&dual, Dual64::from(t), y, out), y, jac);
        true
    }
}

impl Chain {
    /// V(every rod horizontal) − V_min = Σₖ μₖ g lₖ, J.
    fn well_depth(&self) -> f64 {
        let mu = self.hanging::<MAX_LINKS>();
        (0..self.n).map(|k| mu[k] * self.g * self.l[k]).sum()
    }
}

impl Energy for Chain {
    fn energy(&self, _t: f64, y: &[f64]) -> f64 {
        self.kinetic(y) + self.potential(&y[..self.n])
    }
}

/// The chain on (θ, p = M(θ) ω); H = ½ pᵀ M⁻¹ p + V is not separable for n ≥ 2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChainForm {
    /// The chain.
    pub chain: Chain,
}

impl System for ChainForm {
    fn dim(&self) -> usize {
        2 * self.chain.n
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        super::hamilton_rhs(self, t, y, dydt);
    }
    fn jacobian(&self, _t: f64, y: &[f64], jac: &mut [f64]) -> bool {
        let n = self.chain.n;
        let dual = self.chain.dual();
        dual_jacobian(
            2 * n,
            |y, out| {
                let (q, p) = y.split_at(n);
                let (dq, dp) = out.split_at_mut(n);
                dual.velocities(q, p, dq);
                dual.dh_dtheta(q, p, dp);
                for v in dp.iter_mut() {
                    *v = -*v;
                }
            },
            y,
            jac,
        );
        true
    }
}

impl Hamiltonian for ChainForm {
    fn dh_dq(&self, _t: f64, q: &[f64], p: &[f64], out: &mut [f64]) {
        self.chain.dh_dtheta(q, p, out);
    }
    fn dh_dp(&self, _t: f64, q: &[f64], p: &[f64], out: &mut [f64]) {
        self.chain.velocities(q, p, out);
    }
}

impl Energy for ChainForm {
    fn energy(&self, _t: f64, y: &[f64]) -> f64 {
        let n = self.chain.n;
        let mut w = [0.0; MAX_LINKS];
        self.chain.velocities(&y[..n], &y[n..], &mut w);
        0.5 * (0..n).map(|k| y[n + k] * w[k]).sum::<f64>() + self.chain.potential(&y[..n])
    }
}
