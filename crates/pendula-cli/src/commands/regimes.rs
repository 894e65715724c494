//! `pendula oscillator-regimes`: the three damping regimes and forced resonance (the paper's
//! Figure 1 and §2.2), exact and simulated on the same axes.

use anyhow::Result;
use clap::Args;
use pendula::integrator::explicit_rk::RK4;
use pendula::observe::Recorder;
use pendula::system::Model;
use pendula::system::oscillator::Oscillator;
use pendula::{End, RunSpec};
use pendula_viz::{Figure, Kind, palette};
use serde_json::json;

use pendula::error::Short;

use crate::study::{self, Common, OutDir, num};

#[derive(Debug, Clone, Args)]
pub struct RegimesArgs {
    #[command(flatten)]
    pub common: Common,
}

/// Damping ratios of the three regimes.
const REGIMES: [(&str, f64); 3] =
    [("underdamped, ζ = 0.2", 0.2), ("critically damped, ζ = 1", 1.0), ("overdamped, ζ = 3", 3.0)];
/// Damping ratios of the resonance curves.
const RESONANCE: [f64; 4] = [0.05, 0.1, 0.25, 0.7];
/// Step of the simulations, s.
const H: f64 = 0.01;

/// One simulated point of a resonance curve.
pub struct ResonancePoint {
    pub zeta: f64,
    pub ratio: f64,
    pub amplitude_exact: f64,
    pub amplitude_simulated: f64,
    pub phase_exact: f64,
    pub phase_simulated: f64,
}

fn oscillator(set: &[String], extra: &[String]) -> Result<(pendula::system::Values, Oscillator)> {
    let mut items = set.to_vec();
    items.extend_from_slice(extra);
    let values = study::values("oscillator", &items)?;
    let o = Oscillator::from_values(&values);
    Ok((values, o))
}

/// The fastest natural frequency the study's fixed RK4 step resolves, rad/s: at ω₀ H = 0.1
/// the fastest drive (3 ω₀) still gets 20 steps a period, and RK4's error stays below
/// 10⁻⁶ of the amplitude; beyond it the simulated curves stop meaning anything (at ω₀ H ≈ 2.8
/// RK4 is not even stable).
const MAX_NATURAL_FREQUENCY: f64 = 0.1 / H;

/// Checks that the study means something for these parameters: ω₀ = √(k/m) resolved by the
/// step, and the runs (each waits 25 e-folds of its transient, 500/ω₀ s at ζ = 0.05) within
/// the limits.
fn check(args: &RegimesArgs) -> Result<()> {
    crate::parse::refuse_settings(
        &args.common.set.items,
        &["x", "v", "c", "drive_amplitude", "drive_frequency"],
        "oscillator-regimes sets the start, the damping and the drive itself; set k and m only",
    )?;
    let (_, o) = oscillator(&args.common.set.items, &[])?;
    let w0 = o.natural_frequency();
    if w0 > MAX_NATURAL_FREQUENCY {
        anyhow::bail!(
            "oscillator-regimes: w0 = sqrt(k/m) = {} rad/s (k = {} N/m, m = {} kg) is too fast for the study's fixed RK4 step of {H} s, which resolves up to {MAX_NATURAL_FREQUENCY} rad/s: its simulated curves would be meaningless; lower k or raise m",
            Short(w0),
            Short(o.k),
            Short(o.m)
        );
    }
    let ratios: Vec<f64> = (1..=15).map(|k| 0.2 * k as f64).collect();
    let transient = |zeta: f64| 25.0 / (zeta * w0);
    let window = |ratio: f64| 10.0 * std::f64::consts::TAU / (ratio * w0);
    let mut steps: f64 = REGIMES.iter().map(|_| 3.0 * std::f64::consts::TAU / w0 / H).sum();
    for zeta in RESONANCE {
        steps += ratios.iter().map(|r| (transient(zeta) + window(*r)) / H).sum::<f64>();
        steps += (transient(zeta) + window(1.0)) / H;
    }
    crate::limits::check(
        "oscillator-regimes",
        args.common.large.allow_large,
        &[crate::limits::Estimate::new(
            crate::limits::Cost::Steps,
            steps,
            format!(
                "{} runs at w0 = {} rad/s, each past 25 e-folds of its transient",
                3 + 16 * RESONANCE.len(),
                Short(w0)
            ),
        )],
    )
}

pub fn run(args: &RegimesArgs) -> Result<()> {
    check(args)?;
    let mut out = OutDir::new(args.common.out_dir.as_deref(), "oscillator-regimes")?;
    let summary = args.common.summary.open()?;
    let (transients, transient_rows) = transients(&args.common.set.items)?;
    out.csv("transients.csv", &["zeta", "t", "exact", "simulated"], &transient_rows)?;
    let points = resonance(&args.common.set.items)?;
    let rows: Vec<Vec<String>> = points
        .iter()
        .map(|p| {
            vec![
                num(p.zeta),
                num(p.ratio),
                num(p.amplitude_exact),
                num(p.amplitude_simulated),
                num(p.phase_exact),
                num(p.phase_simulated),
            ]
        })
        .collect();
    let header =
        ["zeta", "drive_ratio", "amplitude_exact", "amplitude_simulated", "phase_exact", "phase_simulated"];
    out.csv("resonance.csv", &header, &rows)?;
    let worst_amp =
        points.iter().map(|p| (p.amplitude_simulated / p.amplitude_exact - 1.0).abs()).fold(0.0, f64::max);
    let worst_phase = points.iter().map(|p| (p.phase_simulated - p.phase_exact).abs()).fold(0.0, f64::max);
    let peaks = RESONANCE.iter().map(|&z| peak(&args.common.set.items, z)).collect::<Result<Vec<_>>>()?;
    let shown: Vec<Vec<String>> = RESONANCE
        .iter()
        .zip(&peaks)
        .map(|(&z, peak)| {
            let at =
                |f: fn(&ResonancePoint) -> f64| peak.as_ref().map_or("-".into(), |p| format!("{:.4}", f(p)));
            vec![format!("{z}"), at(|p| p.ratio), at(|p| p.amplitude_exact), at(|p| p.amplitude_simulated)]
        })
        .collect();
    say!(summary, "{}", study::table(&["zeta", "W/w0 at peak", "X k/F exact", "X k/F simulated"], &shown));
    sayln!(
        summary,
        "peaks at W/w0 = sqrt(1 - 2 zeta^2), simulated there; zeta >= 1/sqrt(2) = 0.7071 has no peak (the amplitude falls from W = 0)"
    );
    sayln!(
        summary,
        "largest deviation of simulated from exact: amplitude {worst_amp:.2e} (relative), phase {worst_phase:.2e} rad"
    );
    out.figure("regimes", &transients)?;
    for (name, fig) in resonance_figures(&points) {
        out.figure(name, &fig)?;
    }
    // The summary and the files appear together or not at all.
    out.finish_with(
        summary,
        &json!({
            "max_rel_amplitude_error": worst_amp, "max_phase_error": worst_phase, "dt": H, "method": "rk4",
            "resonance_peaks": RESONANCE.iter().zip(&peaks).map(|(&zeta, p)| json!({
                "zeta": zeta,
                "drive_ratio": p.as_ref().map(|p| p.ratio),
                "amplitude_exact": p.as_ref().map(|p| p.amplitude_exact),
                "amplitude_simulated": p.as_ref().map(|p| p.amplitude_simulated),
            })).collect::<Vec<_>>(),
        }),
    )?;
    Ok(())
}

/// Free decay from x = 1 m at rest in each regime: exact curve and RK4 markers.
pub fn transients(set: &[String]) -> Result<(Figure, Vec<Vec<String>>)> {
    let mut fig = Figure::new(
        "Damped oscillator: the three regimes (paper Figure 1)",
        "time t (s)",
        "displacement x (m)",
    );
    let mut rows = Vec::new();
    for (i, (label, zeta)) in REGIMES.iter().enumerate() {
        let (_, base) = oscillator(set, &[])?;
        let c = 2.0 * zeta * (base.k * base.m).sqrt();
        let (values, o) =
            oscillator(set, &["x=1".into(), "v=0".into(), "drive_amplitude=0".into(), format!("c={c}")])?;
        let period = std::f64::consts::TAU / o.natural_frequency();
        let t_end = 3.0 * period;
        let mut rec = Recorder::default();
        let model = values.build();
        model.solve(
            &RK4,
            values.initial_state(),
            &RunSpec { t0: 0.0, h: H, end: End::Time(t_end) },
            &mut rec,
        )?;
        let samples: Vec<(f64, f64)> = rec.rows.chunks(3).map(|r| (r[0], r[1])).collect();
        let stride = (samples.len() / 40).max(1);
        let exact: Vec<(f64, f64)> =
            (0..=600).map(|k| t_end * k as f64 / 600.0).map(|t| (t, o.exact(t, 1.0, 0.0).0)).collect();
        for (t, x) in samples.iter().step_by(stride) {
            rows.push(vec![num(*zeta), num(*t), num(o.exact(*t, 1.0, 0.0).0), num(*x)]);
        }
        fig = fig.with(format!("{label} (exact)"), palette(i), Kind::Line, exact).with(
            "",
            palette(i),
            Kind::Markers,
            samples.into_iter().step_by(stride).collect(),
        );
    }
    Ok((fig, rows))
}

/// Steady-state amplitude and phase lag against drive frequency: exact, and from RK4 runs
/// past their transient, fitted as x ≈ a cos Ωt + b sin Ωt by least squares.
pub fn resonance(set: &[String]) -> Result<Vec<ResonancePoint>> {
    let ratios: Vec<f64> = (1..=15).map(|k| 0.2 * k as f64).collect();
    let bar = study::progress((RESONANCE.len() * ratios.len()) as u64, "resonance");
    let mut points = Vec::new();
    for &zeta in &RESONANCE {
        for &ratio in &ratios {
            points.push(point(set, zeta, ratio)?);
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    Ok(points)
}

/// The amplitude peak at damping ratio `zeta`, at the exact ω_r = ω₀ √(1 − 2ζ²) and simulated
/// there; `None` for ζ ≥ 1/√2, which has no peak.
pub fn peak(set: &[String], zeta: f64) -> Result<Option<ResonancePoint>> {
    let (_, o) = oscillator(set, &[])?;
    let c = 2.0 * zeta * (o.k * o.m).sqrt();
    let (_, damped) = oscillator(set, &[format!("c={c}")])?;
    damped.resonance_frequency().map(|w| point(set, zeta, w / o.natural_frequency())).transpose()
}

/// One point of a resonance curve: damping ratio `zeta`, drive at `ratio` ω₀.
fn point(set: &[String], zeta: f64, ratio: f64) -> Result<ResonancePoint> {
    let (_, o) = oscillator(set, &[])?;
    let w0 = o.natural_frequency();
    let (c, w) = (2.0 * zeta * (o.k * o.m).sqrt(), ratio * w0);
    let items = [
        format!("c={c}"),
        "drive_amplitude=1".into(),
        format!("drive_frequency={w}"),
        "x=0".into(),
        "v=0".into(),
    ];
    let (values, o) = oscillator(set, &items)?;
    let steady = o.steady_state();
    // Transients decay as e^{−ζ ω₀ t}: wait 25 e-folds, then fit 10 drive periods.
    let transient = 25.0 / (zeta * w0);
    let window = 10.0 * std::f64::consts::TAU / w;
    // The fit's sums are kept, not the run: a slow oscillator waits millions of steps.
    let mut fit = HarmonicFit { w, from: transient, sums: [0.0; 5] };
    let model = values.build();
    let spec = RunSpec { t0: 0.0, h: H, end: End::Time(transient + window) };
    model.solve(&RK4, values.initial_state(), &spec, &mut fit)?;
    let (a, b) = fit.solve();
    let scale = o.drive_amplitude / o.k;
    Ok(ResonancePoint {
        zeta,
        ratio,
        amplitude_exact: steady.amplitude / scale,
        amplitude_simulated: a.hypot(b) / scale,
        phase_exact: steady.phase_lag,
        phase_simulated: b.atan2(a),
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

impl pendula::observe::Observer for HarmonicFit {
    fn observe(&mut self, sample: &pendula::observe::Sample<'_>) -> pendula::observe::Flow {
        if sample.t >= self.from {
            let (s, c) = (self.w * sample.t).sin_cos();
            let x = sample.y[0];
            for (sum, v) in self.sums.iter_mut().zip([c * c, s * s, c * s, x * c, x * s]) {
                *sum += v;
            }
        }
        std::ops::ControlFlow::Continue(())
    }
}

impl HarmonicFit {
    fn solve(&self) -> (f64, f64) {
        let [cc, ss, cs, xc, xs] = self.sums;
        let det = cc * ss - cs * cs;
        ((xc * ss - xs * cs) / det, (xs * cc - xc * cs) / det)
    }
}

/// Amplitude and phase curves: exact lines, simulated markers, one colour per ζ.
pub fn resonance_figures(points: &[ResonancePoint]) -> Vec<(&'static str, Figure)> {
    let mut amp =
        Figure::new("Forced damped oscillator: resonance", "drive frequency Ω / ω₀", "amplitude X k / F");
    let mut phase = Figure::new(
        "Forced damped oscillator: phase lag (π/2 at resonance)",
        "drive frequency Ω / ω₀",
        "phase lag φ (rad)",
    );
    for (i, &zeta) in RESONANCE.iter().enumerate() {
        let curve = |f: &dyn Fn(f64) -> f64| {
            (0..=280).map(|k| 0.2 + k as f64 * 0.01).map(|r| (r, f(r))).collect::<Vec<_>>()
        };
        let exact_amp = move |r: f64| 1.0 / ((1.0 - r * r).powi(2) + (2.0 * zeta * r).powi(2)).sqrt();
        let exact_phase = move |r: f64| (2.0 * zeta * r).atan2(1.0 - r * r);
        let pts: Vec<&ResonancePoint> = points.iter().filter(|p| p.zeta == zeta).collect();
        amp = amp.with(format!("ζ = {zeta}"), palette(i), Kind::Line, curve(&exact_amp)).with(
            "",
            palette(i),
            Kind::Markers,
            pts.iter().map(|p| (p.ratio, p.amplitude_simulated)).collect(),
        );
        phase = phase.with(format!("ζ = {zeta}"), palette(i), Kind::Line, curve(&exact_phase)).with(
            "",
            palette(i),
            Kind::Markers,
            pts.iter().map(|p| (p.ratio, p.phase_simulated)).collect(),
        );
    }
    vec![("resonance_amplitude", amp), ("resonance_phase", phase)]
}
