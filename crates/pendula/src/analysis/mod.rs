//! Analyses of runs: convergence order, energy error and drift, largest stable step,
//! periods from zero crossings, the divergence of nearby trajectories, Lyapunov exponents, Poincaré sections and the flip fractal. Each works on any catalogued model and method.
//!
//! # The analyses
//!
//! Analyses, in `crates/pendula/src/analysis/`, work on any `DynModel` and `Method`:
//! `crates/pendula/src/analysis/convergence.rs` (errors and cost against step, least-squares order
//! fit, reference states: exact where `Model::exact` has one, dop853 at tolerance 1e-14 otherwise;
//! work-precision points over steps for fixed-step methods and over tolerances for the adaptive
//! pairs; `estimate_order`, which finds the asymptotic range — the straight stretch of the log-log
//! curve ending at the smallest step between saturation and ten times the floor (rounding, the
//! reference's `accuracy`, or the level the errors settle at) — without the declared order, and
//! says why when there is none ("step too large", "saturated at round-off", "irregular");
//! `default_ladder`, the per-order ladders of steps), `crates/pendula/src/analysis/energy.rs`
//! (`EnergyBalance`: the energy error relative to the system's declared scale
//! `Model::energy_scale`, or for damped and driven runs the balance E − E(0) − W with the work W of
//! `Model::power` integrated by Simpson's rule on the step's Hermite midpoint; the series, drift
//! rate, envelope, and the bounded/growing verdict `growth`, which asks whether the largest error
//! so far keeps growing over the run's last two doublings of time — a drift's does, a bounded
//! error's on a chaotic orbit only sets an occasional new record),
//! `crates/pendula/src/analysis/stability.rs` (largest stable step by bisection, capped at a
//! method's own step limit, `accepted_step_limit`) and `crates/pendula/src/analysis/period.rs`
//! (zero crossings located by the event observer, periods) and
//! `crates/pendula/src/analysis/divergence.rs` (the distance between two nearby runs and its fitted
//! exponential rate), `crates/pendula/src/analysis/lyapunov.rs` (Benettin's method on the
//! variational system `Tangent`, written over a plain `System` — catalogued models enter through
//! `AsSystem` — so that test-only systems such as the Lorenz equations check it),
//! `crates/pendula/src/analysis/poincare.rs` (starts on an energy surface, section crossings by
//! events, orbits in parallel), `crates/pendula/src/analysis/fractal.rs` (the flip fractal at two
//! steps on the ensemble engine, and its convergence rule) and
//! `crates/pendula/src/analysis/strobe.rs` (stroboscopic samples on the scalar path).

pub mod accuracy;
pub mod compare;
pub mod convergence;
pub mod divergence;
pub mod energy;
pub mod fractal;
pub mod lyapunov;
pub mod period;
pub mod poincare;
pub mod stability;
pub mod strobe;

pub use accuracy::{
    Dropped, MethodConvergence, MethodWork, Problem, all_dropped, convergence_study, nothing_to_run,
    work_precision_study,
};
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
