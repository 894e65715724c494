//! The library's one error type.

/// Everything that can go wrong in pendula, with the values that explain it.
///
/// Invalid input is reported before any work is done; numerical failures carry the
/// simulated time `t` (s) at which they happened.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// No system of this name is in [`crate::system::CATALOGUE`].
    #[error("unknown system `{name}`; valid systems: {valid}")]
    UnknownSystem {
        /// The name asked for.
        name: String,
        /// The valid names, comma-separated.
        valid: String,
    },
    /// No method of this name is in [`crate::integrator::METHODS`].
    #[error("unknown method `{name}`; valid methods: {valid}")]
    UnknownMethod {
        /// The name asked for.
        name: String,
        /// The valid names, comma-separated.
        valid: String,
    },
    /// No preset of this name is in [`crate::system::driven::PRESETS`].
    #[error("unknown preset `{name}`; valid presets: {valid}")]
    UnknownPreset {
        /// The name asked for.
        name: String,
        /// The valid names, comma-separated.
        valid: String,
    },
    /// The system has no parameter or state variable of this name.
    #[error("unknown name `{name}` for system `{system}`; valid names: {valid}")]
    UnknownName {
        /// The system.
        system: &'static str,
        /// The name asked for.
        name: String,
        /// The valid names, comma-separated.
        valid: String,
    },
    /// A value is outside the range its quantity allows.
    #[error("invalid value {value} for `{name}`: {allowed}")]
    InvalidValue {
        /// The parameter, variable or option.
        name: String,
        /// The offending value.
        value: f64,
        /// What is allowed, in words.
        allowed: &'static str,
    },
    /// The method needs structure the system does not have.
    #[error("{method} needs {needs}; {reason}; try {suggestion}")]
    UnmetRequirement {
        /// The method's name.
        method: &'static str,
        /// What the method needs, in words.
        needs: &'static str,
        /// Why the system lacks it, in words.
        reason: String,
        /// Methods that do apply.
        suggestion: &'static str,
    },
    /// The state stopped being finite: the method is unstable at this step size, or the
    /// motion is singular.
    #[error("the state became non-finite at t = {t} s (try a smaller step)")]
    NonFinite {
        /// Time of the first non-finite state, s.
        t: f64,
    },
    /// The step-size controller asked for a step below the minimum.
    #[error(
        "the step size fell to h = {h} s at t = {t} s, below the minimum (loosen the tolerances or lower --h-min)"
    )]
    StepSizeTooSmall {
        /// Time, s.
        t: f64,
        /// The step size proposed, s.
        h: f64,
    },
    /// The iteration that solves an implicit step did not converge (Gauss–Legendre: neither
    /// Newton nor, after it, fixed-point iteration).
    #[error(
        "the implicit step at t = {t} s did not converge (Newton where a Jacobian exists, then {iterations} fixed-point iterations; try a smaller step)"
    )]
    NewtonDidNotConverge {
        /// Time at the start of the failing step, s.
        t: f64,
        /// Iterations performed.
        iterations: usize,
    },
}
