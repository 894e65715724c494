//! `pendula period`: the simple pendulum's period against amplitude — simulated, exact
//! (4 √(l/g) K(sin(θ₀/2))) and small-angle 2π √(l/g) (paper §3; ERRATA on the harmonic
//! approximation).

use anyhow::Result;
use clap::Args;
use pendula::analysis::measure_period;
use pendula::system::Model;
use pendula::system::pendulum::Pendulum;
use pendula_viz::{Figure, Kind, REFERENCE, Scale, method_style, palette};
use serde_json::json;

use crate::args::{Defaults, MethodArgs};
use crate::parse::f64_arg;
use crate::study::{self, Common, OutDir, num};

#[derive(Debug, Clone, Args)]
pub struct PeriodArgs {
    #[command(flatten)]
    pub stepping: MethodArgs,
    /// Largest amplitude, degrees, from 5 to below 180 (a libration: at 180 the pendulum
    /// balances upright and never swings back); amplitudes run in 5° steps up to it.
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub max_amplitude: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

/// One amplitude's periods, s.
pub struct PeriodRow {
    pub amplitude_deg: f64,
    pub simulated: f64,
    pub exact: f64,
    pub small_angle: f64,
}

/// What period runs without arguments (always on the simple pendulum).
pub const DEFAULTS: Defaults =
    crate::args::Defaults::of(&pendula::study::defaults::PERIOD, &[("method", "For the simulated periods.")]);

pub fn run(args: &PeriodArgs) -> Result<()> {
    let method = args.stepping.method(&DEFAULTS)?;
    let h = args.stepping.dt(&DEFAULTS)?;
    let default = DEFAULTS.of.number("max_amplitude");
    let max = f64_arg("--max-amplitude", args.max_amplitude.as_deref(), default, "degrees (5 to < 180)")?;
    let text = args.max_amplitude.clone().unwrap_or_else(|| default.to_string());
    if !(5.0..180.0).contains(&max) {
        anyhow::bail!(
            "invalid --max-amplitude {}: must be from 5 (the first amplitude) to below 180 degrees; the period is of a libration, and at 180 the pendulum balances upright and never swings back",
            crate::parse::clip(&text)
        );
    }
    crate::parse::refuse_settings(
        &args.common.set.items,
        &["theta", "omega"],
        "period releases the pendulum from rest at each amplitude (--max-amplitude); set its parameters only",
    )?;
    crate::parse::schedule(&pendula::RunSpec { t0: 0.0, h, end: pendula::End::Time(1.0) }, "--dt", "--dt")?;
    let amplitudes: Vec<f64> = (1..).map(|k| 5.0 * k as f64).take_while(|a| *a <= max + 1e-9).collect();
    // What it costs: each amplitude runs 2.5 of its exact periods.
    let pendulum = Pendulum::from_values(&study::values("pendulum", &args.common.set.items)?);
    let steps: f64 =
        amplitudes.iter().map(|a| crate::limits::steps(2.5 * pendulum.period(a.to_radians()), h)).sum();
    crate::limits::check(
        "period",
        args.common.large.allow_large,
        &[crate::limits::Estimate::new(
            crate::limits::Cost::Steps,
            steps,
            format!("{} amplitudes x 2.5 periods at dt = {} s", amplitudes.len(), pendula::error::Short(h)),
        )],
    )?;
    let mut out = OutDir::new(args.common.out_dir.as_deref(), "period")?;
    let summary = args.common.summary.open()?;
    let rows = periods(&args.common.set.items, method, h, &amplitudes)?;

    let csv: Vec<Vec<String>> = rows
        .iter()
        .map(|r| vec![num(r.amplitude_deg), num(r.simulated), num(r.exact), num(r.small_angle)])
        .collect();
    out.csv("period.csv", &["amplitude_deg", "simulated", "exact", "small_angle"], &csv)?;
    let shown: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                format!("{}", r.amplitude_deg),
                format!("{:.9}", r.simulated),
                format!("{:.9}", r.exact),
                format!("{:.6}", r.small_angle),
                format!("{:.2e}", (r.simulated / r.exact - 1.0).abs()),
                format!("{:.2e}", (r.small_angle / r.exact - 1.0).abs()),
            ]
        })
        .collect();
    say!(
        summary,
        "{}",
        study::table(
            &[
                "amplitude (deg)",
                "simulated (s)",
                "exact (s)",
                "small-angle (s)",
                "|sim/exact-1|",
                "|small/exact-1|"
            ],
            &shown
        )
    );
    for (name, fig) in figures(&rows, method.name) {
        out.figure(name, &fig)?;
    }
    let worst = rows.iter().map(|r| (r.simulated / r.exact - 1.0).abs()).fold(0.0, f64::max);
    // The summary and the files appear together or not at all.
    out.finish_with(summary,
        &json!({
            "method": method.name, "dt": h,
            "max_rel_error_simulated": worst,
            "rows": rows.iter().map(|r| json!({"amplitude_deg": r.amplitude_deg, "simulated": r.simulated, "exact": r.exact, "small_angle": r.small_angle})).collect::<Vec<_>>(),
        }),
    )?;
    Ok(())
}

/// Simulated, exact and small-angle periods at each amplitude (degrees), from rest.
pub fn periods(
    set: &[String],
    method: &pendula::integrator::Method,
    h: f64,
    amplitudes: &[f64],
) -> Result<Vec<PeriodRow>> {
    let bar = study::progress(amplitudes.len() as u64, "period");
    let mut rows = Vec::new();
    for &a in amplitudes {
        let mut items = set.to_vec();
        items.push(format!("theta={a}deg"));
        items.push("omega=0".into());
        let values = study::values("pendulum", &items)?;
        let pendulum = Pendulum::from_values(&values);
        let theta0 = values.initial_state()[0];
        let exact = pendulum.period(theta0);
        let model = values.build();
        let simulated =
            measure_period(&*model, method, values.initial_state(), 0, h, 2.5 * exact)?.unwrap_or(f64::NAN);
        rows.push(PeriodRow {
            amplitude_deg: a,
            simulated,
            exact,
            small_angle: pendulum.small_angle_period(),
        });
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(rows)
}

/// Period against amplitude, and the relative deviations from the exact period.
pub fn figures(rows: &[PeriodRow], method: &str) -> Vec<(&'static str, Figure)> {
    let pts = |f: fn(&PeriodRow) -> f64| rows.iter().map(|r| (r.amplitude_deg, f(r))).collect::<Vec<_>>();
    let period =
        Figure::new("Simple pendulum: period against amplitude", "amplitude θ₀ (degrees)", "period T (s)")
            .with("exact 4√(l/g) K(sin(θ₀/2))", REFERENCE, Kind::Line, pts(|r| r.exact))
            .with_style(
                format!("simulated ({method})"),
                method_style(method),
                Kind::Markers,
                pts(|r| r.simulated),
            )
            .with("small-angle 2π√(l/g)", palette(4), Kind::Dashed, pts(|r| r.small_angle));
    let error = Figure::new(
        "Simple pendulum: deviation from the exact period",
        "amplitude θ₀ (degrees)",
        "|T / T(exact) − 1|",
    )
    .scales(Scale::Linear, Scale::Log)
    .with_style(
        format!("simulated ({method})"),
        method_style(method),
        Kind::LineMarkers,
        pts(|r| (r.simulated / r.exact - 1.0).abs()),
    )
    .with(
        "small-angle approximation",
        palette(4),
        Kind::LineMarkers,
        pts(|r| (r.small_angle / r.exact - 1.0).abs()),
    );
    vec![("period", period), ("period_error", error)]
}
