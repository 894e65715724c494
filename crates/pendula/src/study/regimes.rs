//! `oscillator-regimes`: the damped oscillator's three regimes and its forced resonance
//! (the paper's Figure 1 and §2.2), exact ([`Oscillator::exact`],
//! [`Oscillator::steady_state`]) and simulated by RK4 on the same axes. The phase lag runs
//! from 0 to π and is π/2 at resonance (ERRATA: not "slightly delayed").
//!
//! The simulated steady state is fitted as x ≈ a cos Ωt + b sin Ωt by least squares over ten
//! drive periods after 25 e-folds of the transient.

use std::f64::consts::TAU;
use std::ops::ControlFlow;

use super::prelude::*;
use crate::error::Short;
use crate::integrator::explicit_rk::RK4;
use crate::observe::{Flow, Observer, Recorder, Sample};
use crate::system::Model;
use crate::system::oscillator::Oscillator;
use crate::{End, Error, RunSpec};

/// The study's entry in [`super::STUDIES`].
pub const STUDY: Study = Study {
    name: "oscillator-regimes",
    about: "The oscillator's damping regimes and forced resonance, exact and simulated",
    params: &[Param::fixed_system("oscillator")],
    files: &["transients", "resonance", "peaks", "regimes", "resonance_amplitude", "resonance_phase"],
    run,
};

/// Damping ratios of the three regimes, with their names.
const REGIMES: [(&str, f64); 3] = [("underdamped", 0.2), ("critically damped", 1.0), ("overdamped", 3.0)];
/// Damping ratios of the resonance curves.
const RESONANCE: [f64; 4] = [0.05, 0.1, 0.25, 0.7];
/// Step of the simulations, s.
const H: f64 = 0.01;
/// The drive frequencies of the resonance curves, in units of ω₀.
fn ratios() -> impl Iterator<Item = f64> {
    (1..=15).map(|k| 0.2 * k as f64)
}

/// The fastest natural frequency the study's fixed RK4 step resolves, rad/s: at ω₀ H = 0.1
/// the fastest drive (3 ω₀) still gets 20 steps a period, and RK4's error stays below
/// 10⁻⁶ of the amplitude; beyond it the simulated curves stop meaning anything (at ω₀ H ≈ 2.8
/// RK4 is not even stable).
const MAX_NATURAL_FREQUENCY: f64 = 0.1 / H;

/// What the study sets itself: the start, the damping and the drive.
const OWN: [&str; 5] = ["x", "v", "c", "drive_amplitude", "drive_frequency"];

/// One simulated point of a resonance curve.
struct Point {
    zeta: f64,
    ratio: f64,
    amplitude_exact: f64,
    amplitude_simulated: f64,
    phase_exact: f64,
    phase_simulated: f64,
}

fn run(inputs: &Inputs, budget: &Budget) -> Result<Report, Error> {
    let args = Args::new(&STUDY, inputs)?;
    if let Some((name, _)) = inputs.set.iter().find(|(n, _)| OWN.contains(&n.as_str())) {
        return Err(Error::InvalidInput {
            name: "set".into(),
            value: name.clone(),
            allowed: "oscillator-regimes sets the start, the damping and the drive itself; set k and m only"
                .into(),
        });
    }
    let base = args.system("system")?;
    let o = Oscillator::from_values(&base);
    let w0 = o.natural_frequency();
    if w0 > MAX_NATURAL_FREQUENCY {
        return Err(Error::InvalidInput {
            name: "set".into(),
            value: format!("k={}, m={}", Short(o.k), Short(o.m)),
            allowed: format!(
                "w0 = sqrt(k/m) = {} rad/s is too fast for the study's fixed RK4 step of {H} s, which resolves up to {MAX_NATURAL_FREQUENCY} rad/s: its simulated curves would be meaningless; lower k or raise m",
                Short(w0)
            ),
        });
    }
    // Each resonance run waits 25 e-folds of its transient (500/ω₀ s at ζ = 0.05).
    let transient = |zeta: f64| 25.0 / (zeta * w0);
    let window = |ratio: f64| 10.0 * TAU / (ratio * w0);
    let mut steps: f64 = REGIMES.len() as f64 * 3.0 * TAU / w0 / H;
    for zeta in RESONANCE {
        steps += ratios().map(|r| (transient(zeta) + window(r)) / H).sum::<f64>();
        steps += (transient(zeta) + window(1.0)) / H;
    }
    budget.afford(
        steps,
        format!(
            "{} runs at w0 = {} rad/s, each past 25 e-folds of its transient",
            REGIMES.len() + 16 * RESONANCE.len(),
            Short(w0)
        ),
    )?;

    let with = |extra: &[(&str, f64)]| {
        let mut s = inputs.set.clone();
        s.extend(extra.iter().map(|(n, v)| ((*n).to_owned(), *v)));
        base.info().values(&s)
    };
    let damping = |zeta: f64| 2.0 * zeta * (o.k * o.m).sqrt();

    // Free decay from x = 1 m at rest in each regime.
    let mut decay = Plot::lines(
        "regimes",
        "Damped oscillator: the three regimes (paper Figure 1)",
        Axis { label: "time t".into(), unit: "s".into(), log: false },
        Axis { label: "displacement x".into(), unit: "m".into(), log: false },
        Vec::new(),
    );
    let mut columns: [Vec<f64>; 4] = Default::default();
    let mut max_decay_error: f64 = 0.0;
    for (label, zeta) in REGIMES {
        let values = with(&[("x", 1.0), ("v", 0.0), ("drive_amplitude", 0.0), ("c", damping(zeta))])?;
        let regime = Oscillator::from_values(&values);
        let t_end = 3.0 * TAU / w0;
        let mut rec = Recorder::default();
        let spec = RunSpec { t0: 0.0, h: H, end: End::Time(t_end) };
        values.build().solve(&RK4, values.initial_state(), &spec, &mut rec)?;
        let samples: Vec<[f64; 2]> = rec.rows.chunks(3).map(|r| [r[0], r[1]]).collect();
        let exact = |t: f64| regime.exact(t, 1.0, 0.0).0;
        max_decay_error = samples.iter().map(|[t, x]| (x - exact(*t)).abs()).fold(max_decay_error, f64::max);
        let stride = (samples.len() / 40).max(1);
        let shown: Vec<[f64; 2]> = samples.into_iter().step_by(stride).collect();
        for [t, x] in &shown {
            for (column, v) in columns.iter_mut().zip([zeta, *t, exact(*t), *x]) {
                column.push(v);
            }
        }
        let curve = (0..=600).map(|k| t_end * f64::from(k) / 600.0).map(|t| [t, exact(t)]).collect();
        decay.series.push(Line::new(format!("{label}, ζ = {zeta} (exact)"), Style::Solid, curve));
        decay.series.push(Line::new(String::new(), Style::Points, shown));
    }
    let [zeta_t, t, exact_t, simulated_t] = columns;

    // The forced steady state against the drive frequency, and at each curve's peak.
    let point = |zeta: f64, ratio: f64| -> Result<Point, Error> {
        let w = ratio * w0;
        let values = with(&[
            ("c", damping(zeta)),
            ("drive_amplitude", 1.0),
            ("drive_frequency", w),
            ("x", 0.0),
            ("v", 0.0),
        ])?;
        let forced = Oscillator::from_values(&values);
        let steady = forced.steady_state();
        // The fit's sums are kept, not the run: a slow oscillator waits millions of steps.
        let mut fit = HarmonicFit { w, from: transient(zeta), sums: [0.0; 5] };
        let spec = RunSpec { t0: 0.0, h: H, end: End::Time(transient(zeta) + window(ratio)) };
        values.build().solve(&RK4, values.initial_state(), &spec, &mut fit)?;
        let (a, b) = fit.solve();
        let scale = forced.drive_amplitude / forced.k;
        Ok(Point {
            zeta,
            ratio,
            amplitude_exact: steady.amplitude / scale,
            amplitude_simulated: a.hypot(b) / scale,
            phase_exact: steady.phase_lag,
            phase_simulated: b.atan2(a),
        })
    };
    let mut points = Vec::new();
    for zeta in RESONANCE {
        for ratio in ratios() {
            points.push(point(zeta, ratio)?);
        }
    }
    let mut peaks = Vec::new();
    for zeta in RESONANCE {
        let damped = Oscillator::from_values(&with(&[("c", damping(zeta))])?);
        peaks.push(damped.resonance_frequency().map(|w| point(zeta, w / w0)).transpose()?);
    }
    let worst_amp =
        points.iter().map(|p| (p.amplitude_simulated / p.amplitude_exact - 1.0).abs()).fold(0.0, f64::max);
    let worst_phase = points.iter().map(|p| (p.phase_simulated - p.phase_exact).abs()).fold(0.0, f64::max);

    let frequency = Axis { label: "drive frequency Ω / ω₀".into(), unit: String::new(), log: false };
    let mut amplitude = Plot::lines(
        "resonance_amplitude",
        "Forced damped oscillator: resonance",
        frequency.clone(),
        Axis { label: "amplitude X k / F".into(), unit: String::new(), log: false },
        Vec::new(),
    );
    let mut phase = Plot::lines(
        "resonance_phase",
        "Forced damped oscillator: phase lag (π/2 at resonance)",
        frequency,
        Axis { label: "phase lag φ".into(), unit: "rad".into(), log: false },
        Vec::new(),
    );
    for zeta in RESONANCE {
        let curve = |f: &dyn Fn(f64) -> f64| -> Vec<[f64; 2]> {
            (0..=280).map(|k| 0.2 + f64::from(k) * 0.01).map(|r| [r, f(r)]).collect()
        };
        let exact_amp = |r: f64| 1.0 / ((1.0 - r * r).powi(2) + (2.0 * zeta * r).powi(2)).sqrt();
        let exact_phase = |r: f64| (2.0 * zeta * r).atan2(1.0 - r * r);
        let ours: Vec<&Point> = points.iter().filter(|p| p.zeta == zeta).collect();
        let label = format!("ζ = {zeta}");
        amplitude.series.push(Line::new(label.clone(), Style::Solid, curve(&exact_amp)));
        amplitude.series.push(Line::new(
            String::new(),
            Style::Points,
            ours.iter().map(|p| [p.ratio, p.amplitude_simulated]).collect(),
        ));
        phase.series.push(Line::new(label, Style::Solid, curve(&exact_phase)));
        phase.series.push(Line::new(
            String::new(),
            Style::Points,
            ours.iter().map(|p| [p.ratio, p.phase_simulated]).collect(),
        ));
    }

    let summary = vec![
        format!(
            "Free decay from x = 1 m at rest (k = {} N/m, m = {} kg, w0 = {} rad/s), underdamped (zeta = 0.2), critically damped (zeta = 1) and overdamped (zeta = 3): RK4 at dt = {H} s stays within {} m of the exact solution",
            Short(o.k),
            Short(o.m),
            sig(w0),
            sig(max_decay_error)
        ),
        format!(
            "Forced steady state at drive frequencies 0.2 to 3 w0 for zeta = 0.05, 0.1, 0.25 and 0.7: simulated amplitudes within {} (relative) and phase lags within {} rad of the exact ones",
            sig(worst_amp),
            sig(worst_phase)
        ),
        "The amplitude peaks at W/w0 = sqrt(1 - 2 zeta^2), simulated there (the table); zeta >= 1/sqrt(2) = 0.7071 has no peak (the amplitude falls from W = 0)".into(),
    ];
    let numbers = vec![
        Number { key: "natural_frequency", value: w0, unit: "rad/s", about: "w0 = sqrt(k/m)" },
        Number { key: "dt", value: H, unit: "s", about: "the step of every RK4 run" },
        Number {
            key: "max_decay_error",
            value: max_decay_error,
            unit: "m",
            about: "max |x(simulated) - x(exact)| of the free decay",
        },
        Number {
            key: "max_rel_amplitude_error",
            value: worst_amp,
            unit: "",
            about: "max |X(simulated) / X(exact) - 1| of the steady state",
        },
        Number {
            key: "max_phase_error",
            value: worst_phase,
            unit: "rad",
            about: "max |phase(simulated) - phase(exact)| of the steady state",
        },
    ];
    let col = |name: &'static str, unit: &'static str, f: fn(&Point) -> f64, of: &[&Point]| {
        Column::numbers(name, unit, of.iter().map(|p| f(p)).collect())
    };
    let all: Vec<&Point> = points.iter().collect();
    let at_peaks: Vec<Option<&Point>> = peaks.iter().map(Option::as_ref).collect();
    let peak_col = |name: &'static str, f: fn(&Point) -> f64| {
        Column::numbers(name, "", at_peaks.iter().map(|p| p.map_or(f64::NAN, f)).collect())
    };
    let tables = vec![
        Table {
            name: "transients",
            shown: false,
            columns: vec![
                Column::numbers("zeta", "", zeta_t),
                Column::numbers("t", "s", t),
                Column::numbers("exact", "m", exact_t),
                Column::numbers("simulated", "m", simulated_t),
            ],
        },
        Table {
            name: "resonance",
            shown: false,
            columns: vec![
                col("zeta", "", |p| p.zeta, &all),
                col("drive_ratio", "", |p| p.ratio, &all),
                col("amplitude_exact", "", |p| p.amplitude_exact, &all),
                col("amplitude_simulated", "", |p| p.amplitude_simulated, &all),
                col("phase_exact", "rad", |p| p.phase_exact, &all),
                col("phase_simulated", "rad", |p| p.phase_simulated, &all),
            ],
        },
        Table {
            name: "peaks",
            shown: true,
            columns: vec![
                Column::numbers("zeta", "", RESONANCE.to_vec()),
                peak_col("drive_ratio", |p| p.ratio),
                peak_col("amplitude_exact", |p| p.amplitude_exact),
                peak_col("amplitude_simulated", |p| p.amplitude_simulated),
            ],
        },
    ];
    Ok(Report {
        study: STUDY.name,
        inputs: vec![("system", Input::Name(base.info().name.into()))],
        summary,
        numbers,
        texts: Vec::new(),
        tables,
        plots: vec![decay, amplitude, phase],
    })
}

/// Least-squares (a, b) in x(t) ≈ a cos(ω t) + b sin(ω t) over the samples from t = `from`
/// on, accumulated as they come.
struct HarmonicFit {
    w: f64,
    from: f64,
    /// Σ cos², Σ sin², Σ cos sin, Σ x cos, Σ x sin.
    sums: [f64; 5],
}

impl Observer for HarmonicFit {
    fn observe(&mut self, sample: &Sample<'_>) -> Flow {
        if sample.t >= self.from {
            let (s, c) = (self.w * sample.t).sin_cos();
            let x = sample.y[0];
            for (sum, v) in self.sums.iter_mut().zip([c * c, s * s, c * s, x * c, x * s]) {
                *sum += v;
            }
        }
        ControlFlow::Continue(())
    }
}

impl HarmonicFit {
    fn solve(&self) -> (f64, f64) {
        let [cc, ss, cs, xc, xs] = self.sums;
        let det = cc * ss - cs * cs;
        ((xc * ss - xs * cs) / det, (xs * cc - xc * cs) / det)
    }
}
