//! Symmetric compositions of Störmer–Verlet: higher even orders from the second-order,
//! symmetric, symplectic leapfrog, for separable Hamiltonians H = T(p) + V(t, q).
//!
//! A composition takes Verlet steps of sizes w₁h, w₂h, …, wₛh with Σ wᵢ = 1; the weights
//! are symmetric (wᵢ = wₛ₊₁₋ᵢ), so the result is symmetric and symplectic, and chosen so the
//! error terms up to the stated order cancel. Some weights are negative (steps backwards),
//! and |wᵢ| up to ~2 shrink the stable step size accordingly.
//!
//! Requirements: a separable Hamiltonian. On the double pendulum (not separable) use
//! `verlet` or `symplectic-euler`, which are implicit there.
//!
//! # References
//! - H. Yoshida, "Construction of higher order symplectic integrators", Phys. Lett. A 150
//!   (1990) 262–268: the triple jump (order 4), solution A of order 6 (7 stages) and solution
//!   D of order 8 (15 stages).
//! - E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, §II.4 and §V.3.

use super::partitioned::Partition;
use super::{Method, Requirement, Scheme};

/// 2^(1/3), for the triple jump.
const CBRT_2: f64 = 1.259_921_049_894_873_2;
/// The triple jump's outer weight 1 / (2 − 2^(1/3)).
const TJ: f64 = 1.0 / (2.0 - CBRT_2);

/// Yoshida's triple jump, order 4: weights γ, 1 − 2γ, γ with γ = 1/(2 − 2^(1/3)).
pub const YOSHIDA_4_WEIGHTS: [f64; 3] = [TJ, 1.0 - 2.0 * TJ, TJ];

/// Yoshida's solution A of order 6 (w₁, w₂, w₃ as the exact roots of his order conditions,
/// to more digits than the 15 published).
const Y6: [f64; 3] = [-1.177_679_984_178_871, 0.235_573_213_359_358_13, 0.784_513_610_477_557_3];
/// The order-6 weights w₃ w₂ w₁ w₀ w₁ w₂ w₃, w₀ = 1 − 2(w₁ + w₂ + w₃).
pub const YOSHIDA_6_WEIGHTS: [f64; 7] =
    [Y6[2], Y6[1], Y6[0], 1.0 - 2.0 * (Y6[0] + Y6[1] + Y6[2]), Y6[0], Y6[1], Y6[2]];

/// Yoshida's solution D of order 8, w₁ … w₇ as published (15 digits).
const Y8: [f64; 7] = [
    0.102_799_849_391_985,
    -1.960_610_232_975_49,
    1.938_139_137_622_76,
    -0.158_240_635_368_243,
    -1.444_852_236_860_48,
    0.253_693_336_566_229,
    0.914_844_246_229_740,
];
const Y8_0: f64 = 1.0 - 2.0 * (Y8[0] + Y8[1] + Y8[2] + Y8[3] + Y8[4] + Y8[5] + Y8[6]);
/// The order-8 weights w₇ … w₁ w₀ w₁ … w₇.
pub const YOSHIDA_8_WEIGHTS: [f64; 15] =
    [Y8[6], Y8[5], Y8[4], Y8[3], Y8[2], Y8[1], Y8[0], Y8_0, Y8[0], Y8[1], Y8[2], Y8[3], Y8[4], Y8[5], Y8[6]];

/// Yoshida's 4th-order triple jump over Störmer–Verlet (3 force evaluations per step).
///
/// Requirements: a separable Hamiltonian.
///
/// # References
/// Yoshida, Phys. Lett. A 150 (1990) 262, (4.4).
pub static YOSHIDA_4: Method = Method {
    name: "yoshida-4",
    title: "Yoshida triple jump",
    order: 4,
    requirement: Requirement::Separable,
    symplectic: true,
    symmetric: true,
    description: "3 Verlet steps (triple jump), explicit; separable systems only",
    reference: "Yoshida, Phys. Lett. A 150 (1990) 262, (4.4)",
    scheme: Scheme::Partitioned(Partition::Composition(&YOSHIDA_4_WEIGHTS)),
};

/// Yoshida's 6th-order composition, solution A (7 Verlet steps).
///
/// Requirements: a separable Hamiltonian.
///
/// # References
/// Yoshida, Phys. Lett. A 150 (1990) 262, Table 1, solution A.
pub static YOSHIDA_6: Method = Method {
    name: "yoshida-6",
    title: "Yoshida order 6 (solution A)",
    order: 6,
    requirement: Requirement::Separable,
    symplectic: true,
    symmetric: true,
    description: "7 Verlet steps, explicit; separable systems only",
    reference: "Yoshida, Phys. Lett. A 150 (1990) 262, Table 1, solution A",
    scheme: Scheme::Partitioned(Partition::Composition(&YOSHIDA_6_WEIGHTS)),
};

/// Yoshida's 8th-order composition, solution D (15 Verlet steps).
///
/// Requirements: a separable Hamiltonian.
///
/// # References
/// Yoshida, Phys. Lett. A 150 (1990) 262, Table 2, solution D.
pub static YOSHIDA_8: Method = Method {
    name: "yoshida-8",
    title: "Yoshida order 8 (solution D)",
    order: 8,
    requirement: Requirement::Separable,
    symplectic: true,
    symmetric: true,
    description: "15 Verlet steps, explicit; separable systems only",
    reference: "Yoshida, Phys. Lett. A 150 (1990) 262, Table 2, solution D",
    scheme: Scheme::Partitioned(Partition::Composition(&YOSHIDA_8_WEIGHTS)),
};
