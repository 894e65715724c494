//! Elliptic integrals and Jacobi elliptic functions, for the pendulum's exact solution.
//!
//! Everything takes the *modulus* k (not the parameter m = k²), as the pendulum's
//! formulas do: the period from rest at amplitude θ₀ is 4 √(l/g) K(sin(θ₀/2)).
//!
//! # References
//! - B. C. Carlson, "Numerical computation of real or complex elliptic integrals",
//!   Numer. Algorithms 10 (1995) 13–26 (the duplication algorithm for R_F).
//! - M. Abramowitz, I. A. Stegun, *Handbook of Mathematical Functions* (1964), §16.4
//!   (Jacobi functions by the descending arithmetic-geometric mean) and §17.6 (K by the AGM).

use std::f64::consts::PI;

/// Complete elliptic integral of the first kind K(k) = ∫₀^{π/2} dφ / √(1 − k² sin² φ),
/// for modulus 0 ≤ |k| < 1 (infinite at |k| = 1, NaN beyond).
pub fn ellip_k(k: f64) -> f64 {
    let m = k * k;
    if m == 1.0 {
        return f64::INFINITY;
    }
    if m > 1.0 || m.is_nan() {
        return f64::NAN;
    }
    // K = π / (2 AGM(1, k')), with k' computed as √((1−k)(1+k)) to keep digits near k = 1.
    let (mut a, mut b) = (1.0, ((1.0 - k.abs()) * (1.0 + k.abs())).sqrt());
    // The AGM converges quadratically; 2 ulp is as close as a and b get in f64.
    for _ in 0..64 {
        if (a - b).abs() <= 2.0 * f64::EPSILON * a {
            break;
        }
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    PI / (a + b)
}

/// Carlson's symmetric integral R_F(x, y, z) = ½ ∫₀^∞ dt / √((t+x)(t+y)(t+z)),
/// for x, y, z ≥ 0 with at most one of them zero.
pub fn carlson_rf(x: f64, y: f64, z: f64) -> f64 {
    let (mut x, mut y, mut z) = (x, y, z);
    loop {
        let mu = (x + y + z) / 3.0;
        let (dx, dy, dz) = (1.0 - x / mu, 1.0 - y / mu, 1.0 - z / mu);
        // The truncation error of the series below is O(max|d|⁶); 1e-3 leaves < 1e-17.
        if dx.abs().max(dy.abs()).max(dz.abs()) < 1e-3 {
            let e2 = dx * dy - dz * dz;
            let e3 = dx * dy * dz;
            return (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / mu.sqrt();
        }
        let (sx, sy, sz) = (x.sqrt(), y.sqrt(), z.sqrt());
        let lambda = sx * (sy + sz) + sy * sz;
        x = 0.25 * (x + lambda);
        y = 0.25 * (y + lambda);
        z = 0.25 * (z + lambda);
    }
}

/// Incomplete elliptic integral of the first kind F(φ, k) = ∫₀^φ dψ / √(1 − k² sin² ψ),
/// for any real φ and modulus |k| < 1; F(φ + π, k) = F(φ, k) + 2 K(k).
pub fn ellip_f(phi: f64, k: f64) -> f64 {
    let turns = (phi / PI).round();
    let r = phi - turns * PI;
    let (s, c) = r.sin_cos();
    let partial = s * carlson_rf(c * c, 1.0 - k * k * s * s, 1.0);
    if turns == 0.0 { partial } else { partial + 2.0 * turns * ellip_k(k) }
}

/// Jacobi elliptic functions at argument u for modulus 0 ≤ |k| < 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jacobi {
    /// The amplitude am(u, k): the φ with F(φ, k) = u (continuous and increasing in u).
    pub am: f64,
    /// sn(u, k) = sin am.
    pub sn: f64,
    /// cn(u, k) = cos am.
    pub cn: f64,
    /// dn(u, k) = √(1 − k² sn²).
    pub dn: f64,
}

/// Jacobi elliptic functions by the descending AGM (Abramowitz & Stegun 16.4).
pub fn jacobi(u: f64, k: f64) -> Jacobi {
    let m = k * k;
    // At most ~10 AGM steps are needed for m < 1 - 1e-300; 32 is a safe bound.
    let mut a = [0.0_f64; 32];
    let mut c = [0.0_f64; 32];
    a[0] = 1.0;
    c[0] = k.abs();
    let mut b = ((1.0 - k.abs()) * (1.0 + k.abs())).sqrt();
    let mut n = 0;
    while c[n].abs() > f64::EPSILON * a[n] && n + 1 < a.len() {
        a[n + 1] = 0.5 * (a[n] + b);
        c[n + 1] = 0.5 * (a[n] - b);
        b = (a[n] * b).sqrt();
        n += 1;
    }
    let mut phi = (1u64 << n) as f64 * a[n] * u;
    for i in (1..=n).rev() {
        phi = 0.5 * (phi + (c[i] / a[i] * phi.sin()).asin());
    }
    let (sn, cn) = phi.sin_cos();
    Jacobi { am: phi, sn, cn, dn: (1.0 - m * sn * sn).sqrt() }
}
