//! The flip fractal: the time a double pendulum released from rest at (θ₁, θ₂) takes to
//! flip (either rod passes ±π), over a grid of starts, on the ensemble engine — computed at
//! two step sizes, so that every pixel carries a convergence flag.

use crate::Error;
use crate::ensemble::engine::{self, LaneMethod, LaneOutcome, LaneSpec};
use crate::system::Model;
use crate::system::double::DoublePendulum;

/// The methods the fractal runs: those the ensemble engine runs on the free double pendulum
/// ([`crate::model::lane_method`]), in the catalogue's order.
pub fn methods() -> Vec<&'static str> {
    crate::integrator::METHODS.iter().filter(|m| lane_method(m).is_some()).map(|m| m.name).collect()
}

/// How the engine runs `method` on the free double pendulum, if it does.
fn lane_method(method: &'static crate::integrator::Method) -> Option<LaneMethod> {
    crate::model::lane_method(method, &DoublePendulum::default())
}

/// One axis of the grid: `n` cell centres lo + (i + ½)(hi − lo)/n (the convention of
/// `pendula sweep`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridAxis {
    /// Lower edge, rad.
    pub lo: f64,
    /// Upper edge, rad.
    pub hi: f64,
    /// Number of cells.
    pub n: usize,
}

impl GridAxis {
    /// The centre of cell i.
    pub fn centre(&self, i: usize) -> f64 {
        self.lo + (i as f64 + 0.5) * (self.hi - self.lo) / self.n as f64
    }
}

impl From<(f64, f64, usize)> for GridAxis {
    /// (lo, hi, n), as Python passes an axis.
    fn from((lo, hi, n): (f64, f64, usize)) -> Self {
        GridAxis { lo, hi, n }
    }
}

/// What to compute.
#[derive(Debug, Clone, Copy)]
pub struct FractalSpec {
    /// The pendulum (undamped and undriven: the ensemble kernels' equations).
    pub pendulum: DoublePendulum,
    /// θ₁ axis (varies fastest in the output).
    pub theta1: GridAxis,
    /// θ₂ axis.
    pub theta2: GridAxis,
    /// Longest time followed, s; no flip by then is NaN.
    pub t_max: f64,
    /// Step size of the main run, s; the check runs at h/2.
    pub h: f64,
    /// The method, as the ensemble engine runs it ([`methods`]).
    pub method: LaneMethod,
    /// A pixel is converged when its flip times at h and h/2 differ by at most this, s (and
    /// both or neither flip).
    pub tolerance: f64,
}

impl FractalSpec {
    /// The fractal of the double pendulum `values` (its parameters; it starts from rest at
    /// each pixel) over `theta1` × `theta2`, at steps `dt` and `dt`/2 of `method` to `t_max`,
    /// converged within `tolerance` (s), checked before any work. Errors name the inputs as
    /// every front end's keywords do (`dt`, `t_max`, `tolerance`, `method`, `theta1`), and
    /// `set` for the pendulum's own settings.
    ///
    /// # Errors
    /// Another system, a damped or driven pendulum (the ensemble kernels integrate the free
    /// one), an empty or reversed axis, times not finite and > 0, `dt` above `t_max`, a
    /// negative tolerance, a method the ensemble engine does not run, or a Tao step above
    /// its limit.
    pub fn new(
        values: &crate::system::Values,
        theta1: GridAxis,
        theta2: GridAxis,
        t_max: f64,
        dt: f64,
        method: &'static crate::integrator::Method,
        tolerance: f64,
    ) -> Result<FractalSpec, Error> {
        let info = values.info();
        let invalid = |name: &str, value: String, allowed: String| Error::InvalidInput {
            name: name.into(),
            value,
            allowed,
        };
        if info.name != "double" {
            return Err(invalid(
                "system",
                info.name.into(),
                "the flip fractal is the double pendulum's (`double`)".into(),
            ));
        }
        let pendulum = <DoublePendulum as crate::system::Model>::from_values(values);
        if pendulum.is_forced() {
            let forcing = ["damping", "drive_amplitude"]
                .into_iter()
                .find(|q| values.get(q) != 0.0)
                .map(|q| format!("{q}={}", crate::error::Short(values.get(q))));
            return Err(invalid(
                "set",
                forcing.unwrap_or_default(),
                "the fractal's ensemble kernels integrate the free double pendulum (damping and drive_amplitude must be 0)"
                    .into(),
            ));
        }
        for (name, a) in [("theta1", theta1), ("theta2", theta2)] {
            if !(a.lo.is_finite() && a.hi.is_finite() && a.lo < a.hi && a.n >= 1) {
                return Err(invalid(
                    name,
                    format!("({}, {}, {})", a.lo, a.hi, a.n),
                    "(lo, hi, n) with finite lo < hi (rad) and n >= 1".into(),
                ));
            }
        }
        for (name, v) in [("t_max", t_max), ("dt", dt)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::InvalidValue {
                    name: name.into(),
                    value: v,
                    allowed: "must be finite and > 0",
                });
            }
        }
        if dt > t_max {
            return Err(invalid(
                "dt",
                crate::error::Short(dt).to_string(),
                format!("must be at most `t_max` {}", crate::error::Short(t_max)),
            ));
        }
        if !(tolerance.is_finite() && tolerance >= 0.0) {
            return Err(Error::InvalidValue {
                name: "tolerance".into(),
                value: tolerance,
                allowed: "must be finite and >= 0 (s)",
            });
        }
        let Some(batch) = lane_method(method) else {
            return Err(invalid(
                "method",
                method.name.into(),
                format!("the fractal runs on the ensemble engine: {}", methods().join(", ")),
            ));
        };
        if let Some(refusal) = crate::integrator::tao::step_refusal(method, dt) {
            return Err(refusal);
        }
        Ok(FractalSpec { pendulum, theta1, theta2, t_max, h: dt, method: batch, tolerance })
    }
}

/// The result of [`flip_fractal`]: arrays of θ₂-rows of θ₁-pixels (θ₁ fastest).
#[derive(Debug, Clone, PartialEq)]
pub struct FlipFractal {
    /// Time to the first flip at step h, s; NaN where none happens before `t_max`.
    pub flip_time: Vec<f64>,
    /// The same at step h/2.
    pub flip_time_half_step: Vec<f64>,
    /// Whether the two agree ([`converged`]).
    pub converged: Vec<bool>,
    /// Pixels whose energy forbids any flip ([`cannot_flip`]), not integrated.
    pub forbidden: usize,
}

/// Whether a pendulum released from rest at (θ₁, θ₂) can never flip: its energy is below
/// the least potential energy with a rod upright, min((m₁+m₂) g l₁ − m₂ g l₂,
/// m₂ g l₂ − (m₁+m₂) g l₁) (θ₁ = π with θ₂ = 0, or θ₂ = π with θ₁ = 0). Conservation of
/// energy then keeps both angles inside (−π, π) for ever.
pub fn cannot_flip(p: &DoublePendulum, theta1: f64, theta2: f64) -> bool {
    let (a, b) = ((p.m1 + p.m2) * p.g * p.l1, p.m2 * p.g * p.l2);
    let energy = -a * theta1.cos() - b * theta2.cos();
    energy < (a - b).min(b - a)
}

/// The convergence rule: both NaN, or both finite and within `tolerance` of each other.
pub fn converged(coarse: f64, fine: f64, tolerance: f64) -> bool {
    match (coarse.is_nan(), fine.is_nan()) {
        (true, true) => true,
        (false, false) => (coarse - fine).abs() <= tolerance,
        _ => false,
    }
}

/// Computes the flip fractal, on rayon's current pool: results do not depend on its size.
///
/// # Errors
/// [`Error::UnmetRequirement`] for Tao's map on a forced pendulum; [`Error::NonFiniteMember`]
/// for a non-finite state (member = pixel index).
///
/// # Panics
/// If `h` or `t_max` is not finite and positive (validated by the caller).
pub fn flip_fractal(spec: &FractalSpec) -> Result<FlipFractal, Error> {
    flip_fractal_with_progress(spec, &|_| ())
}

/// [`flip_fractal`], reporting progress to `tick(n)` (n pixel-runs done, from any thread):
/// 2 × the pixels in all, the forbidden ones at once.
///
/// # Errors
/// As [`flip_fractal`].
///
/// # Panics
/// As [`flip_fractal`].
pub fn flip_fractal_with_progress(
    spec: &FractalSpec,
    tick: &(dyn Fn(u64) + Sync),
) -> Result<FlipFractal, Error> {
    let pixels = spec.theta1.n * spec.theta2.n;
    let (flip_time, flip_time_half_step) = flip_times(spec, 0..pixels, tick)?;
    Ok(assemble(spec, flip_time, flip_time_half_step))
}

/// The flip times at h and at h/2 of the pixels in `pixels` (indices with θ₁ fastest), NaN
/// where none happens before `t_max` or the energy forbids it, reporting progress to `tick`
/// as [`flip_fractal_with_progress`] does. A pixel's times do not depend on which others
/// are computed with it, so a fractal computed in ranges (and continued from a checkpoint)
/// is bitwise the fractal computed at once.
///
/// # Errors
/// As [`flip_fractal`] (member = pixel index).
///
/// # Panics
/// As [`flip_fractal`], and if the range is outside the grid.
pub fn flip_times(
    spec: &FractalSpec,
    pixels: std::ops::Range<usize>,
    tick: &(dyn Fn(u64) + Sync),
) -> Result<(Vec<f64>, Vec<f64>), Error> {
    flip_times_cancellable(spec, pixels, tick, None)
}

/// [`flip_times`], stopped early when `cancel` is set: the engine looks at it before each
/// lane group ([`LaneSpec::cancel`]), so that one call over the whole
/// map keeps every thread busy to the end and still stops promptly.
///
/// # Errors
/// As [`flip_times`], and [`Error::Interrupted`] when `cancel` was set.
///
/// # Panics
/// As [`flip_times`].
pub fn flip_times_cancellable(
    spec: &FractalSpec,
    pixels: std::ops::Range<usize>,
    tick: &(dyn Fn(u64) + Sync),
    cancel: Option<&std::sync::atomic::AtomicBool>,
) -> Result<(Vec<f64>, Vec<f64>), Error> {
    assert!(spec.h > 0.0 && spec.t_max > 0.0 && spec.t_max.is_finite(), "validated step and end");
    Ok((
        flip_times_at(spec, spec.h, pixels.clone(), tick, cancel)?,
        flip_times_at(spec, spec.h / 2.0, pixels, tick, cancel)?,
    ))
}

/// The flip times of the pixels in `pixels` at the one step size `h` (half of
/// [`flip_times_cancellable`]'s work: `pendula serve` draws its coarse previews from this
/// alone, and the convergence check only for the finished map), NaN where none happens
/// before `t_max` or the energy forbids it. Progress as [`flip_times`] counts it, one tick
/// per pixel.
///
/// # Errors
/// As [`flip_times_cancellable`].
///
/// # Panics
/// If `h` or `t_max` is not finite and positive, or the range is outside the grid.
pub fn flip_times_at(
    spec: &FractalSpec,
    h: f64,
    pixels: std::ops::Range<usize>,
    tick: &(dyn Fn(u64) + Sync),
    cancel: Option<&std::sync::atomic::AtomicBool>,
) -> Result<Vec<f64>, Error> {
    assert!(h > 0.0 && spec.t_max > 0.0 && spec.t_max.is_finite(), "validated step and end");
    let n1 = spec.theta1.n;
    assert!(pixels.end <= n1 * spec.theta2.n, "pixels inside the grid");
    let start = |i: usize| (spec.theta1.centre(i % n1), spec.theta2.centre(i / n1));
    // Only pixels that can flip are integrated; the others are NaN.
    let allowed: Vec<usize> = pixels
        .clone()
        .filter(|&i| {
            let (a, b) = start(i);
            !cannot_flip(&spec.pendulum, a, b)
        })
        .collect();
    tick((pixels.len() - allowed.len()) as u64);
    let steps = (spec.t_max / h).ceil() as u64;
    let lanes = LaneSpec { method: spec.method, h, steps, stop_at_flip: true, track_flips: true, cancel };
    let d = spec.pendulum;
    let member = |k: usize, v: &mut [f64]| {
        let (a, b) = start(allowed[k]);
        let p = [d.m1, d.m2, d.l1, d.l2, d.g, d.damping, d.drive_amplitude, d.drive_frequency];
        v[..8].copy_from_slice(&p);
        v[8..].copy_from_slice(&[a, b, 0.0, 0.0]);
    };
    let mut times = vec![f64::NAN; allowed.len()];
    let store = |_: usize, r: &LaneOutcome, row: &mut [f64]| {
        row[0] = if r.flip_time <= spec.t_max { r.flip_time } else { f64::NAN };
        tick(1);
    };
    let members = engine::Members { info: DoublePendulum::INFO, count: allowed.len(), values: &member };
    engine::run::<DoublePendulum, _>(
        &members,
        &lanes,
        engine::Rows { out: &mut times, len: 1, store: &store },
    )
    .map_err(|e| match e {
        Error::NonFiniteMember { member, t } => Error::NonFiniteMember { member: allowed[member], t },
        other => other,
    })?;
    let mut image = vec![f64::NAN; pixels.len()];
    for (k, t) in allowed.iter().zip(times) {
        image[*k - pixels.start] = t;
    }
    Ok(image)
}

/// The fractal of the flip times of every pixel at h and at h/2 ([`flip_times`]): the
/// convergence flags and the count of pixels the energy forbids.
pub fn assemble(spec: &FractalSpec, flip_time: Vec<f64>, flip_time_half_step: Vec<f64>) -> FlipFractal {
    let n1 = spec.theta1.n;
    let forbidden = (0..flip_time.len())
        .filter(|&i| cannot_flip(&spec.pendulum, spec.theta1.centre(i % n1), spec.theta2.centre(i / n1)))
        .count();
    let converged =
        flip_time.iter().zip(&flip_time_half_step).map(|(a, b)| converged(*a, *b, spec.tolerance)).collect();
    FlipFractal { flip_time, flip_time_half_step, converged, forbidden }
}
