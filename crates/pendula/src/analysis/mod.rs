//! Analyses of runs: convergence order, energy error and drift, largest stable step,
//! periods from zero crossings, the divergence of nearby trajectories, Lyapunov exponents, Poincaré sections and the flip fractal. Each works on any catalogued model and method.

pub mod convergence;
pub mod divergence;
pub mod energy;
pub mod fractal;
pub mod lyapunov;
pub mod period;
pub mod poincare;
pub mod stability;
pub mod strobe;

pub use convergence::{
    DEFAULT_LEVELS, FLOOR_MARGIN, MIN_SPAN, OrderEstimate, OrderFit, REFERENCE_TOLERANCE, Reference,
    SATURATION, STRAIGHT, WorkPoint, convergence_errors, default_ladder, estimate_order, fit_order,
    method_ladder, reference_state, roundoff_floor, study_horizon, tolerance_ladder, work_precision,
    work_precision_adaptive,
};
pub use divergence::{Divergence, GrowthFit, divergence, growth_rate, growth_rate_between};
pub use energy::{
    EnergyBalance, EnergySeries, GROWTH_FACTOR, Growth, drift_rate, envelope, first_exceeding, growth,
};
pub use lyapunov::{Lyapunov, LyapunovSpec, Tangent, lyapunov};
pub use period::measure_period;
pub use stability::{StabilityCriterion, accepted_step_limit, is_stable, largest_stable_step};
