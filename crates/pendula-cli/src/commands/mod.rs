//! The study commands, one file each.

pub mod animate;
pub mod bifurcation;
pub mod compare;
pub mod convergence;
pub mod divergence;
pub mod fractal;
pub mod lyapunov;
pub mod merge;
pub mod period;
pub mod plot;
pub mod poincare;
pub mod regimes;
pub mod report;
pub mod resume;
pub mod serve;
pub mod stability;
pub mod sweep;
pub mod work_precision;
