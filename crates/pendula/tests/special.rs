//! Elliptic functions against mpmath (30 digits; `reference/mpmath_reference.py`).

use pendula::special::{ellip_f, ellip_k, jacobi};

fn close(a: f64, b: f64, tol: f64) {
    assert!((a - b).abs() <= tol * b.abs().max(1.0), "{a} vs {b}");
}

#[test]
fn ref_complete_integral_k() {
    close(ellip_k(0.0), std::f64::consts::FRAC_PI_2, 1e-15);
    close(ellip_k(0.5), 1.6857503548125960429, 1e-15);
    close(ellip_k(0.9), 2.2805491384227702046, 1e-15);
    close(ellip_k(0.999), 4.4955963958421441704, 1e-14);
    // Closed form: K(1/√2) = Γ(1/4)² / (4 √π).
    close(ellip_k(std::f64::consts::FRAC_1_SQRT_2), 1.854_074_677_301_371_9, 1e-15);
    assert!(ellip_k(1.0).is_infinite());
}

#[test]
fn ref_incomplete_integral_f() {
    close(ellip_f(0.7, 0.5), 0.71362050286777775343, 1e-15);
    close(ellip_f(2.5, 0.8), 3.3198755177924326235, 1e-15);
    close(ellip_f(-4.0, 0.3), -4.0828941483153437994, 1e-15);
    close(ellip_f(std::f64::consts::FRAC_PI_2, 0.9), ellip_k(0.9), 1e-15);
}

#[test]
fn ref_jacobi_functions() {
    for (u, k, sn, cn, dn) in [
        (0.6, 0.5, 0.55773380237106149078, 0.83001988270927445525, 0.96032976181266996644),
        (3.7, 0.95, 0.91613378198440019712, -0.40087266495354792253, 0.49247411240595270366),
        (-2.2, 0.2, -0.82412216676355272134, -0.5664120887207007681, 0.98632292185164077729),
    ] {
        let j = jacobi(u, k);
        close(j.sn, sn, 1e-14);
        close(j.cn, cn, 1e-14);
        close(j.dn, dn, 1e-14);
        close(ellip_f(j.am, k), u, 1e-14);
    }
    // k = 0: sn = sin.
    close(jacobi(1.3, 0.0).sn, 1.3f64.sin(), 1e-15);
}
