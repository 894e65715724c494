//! `pendula poincare`: a Poincaré section of a conservative two-degree-of-freedom system
//! (the double pendulum by default): orbits started on a fixed-energy surface, their
//! crossings of θₛ = v (mod 2π) with θ̇ₛ > 0 located by events, as a scatter of the other
//! angle and its momentum coloured by orbit.

use anyhow::{Result, bail};
use clap::Args;
use pendula::analysis::poincare::{PoincareSpec, Stepping, poincare};
use pendula::control::Tolerances;
use pendula::error::{did_you_mean, suggestions};
use pendula::integrator::Scheme;
use pendula_viz::{Figure, Kind, Scale, axis_label, number, palette, pretty, with_unit};
use serde_json::json;

use crate::args::{Defaults, EndArg, MethodArgs, SystemArg};
use crate::limits::{self, Cost, Estimate};
use crate::parse::{clip, parse_count, parse_float, parse_value, refuse_settings};
use crate::study::{self, Common, OutDir, num};

#[derive(Debug, Clone, Args)]
pub struct PoincareArgs {
    #[command(flatten)]
    pub system: SystemArg,
    /// Energy of every orbit, J.
    #[arg(long, value_name = "E", allow_hyphen_values = true)]
    pub energy: Option<String>,
    /// Number of orbits, 1 to 10000.
    #[arg(long, value_name = "N")]
    pub count: Option<String>,
    /// The section, an angle and its value (deg accepted); crossings count when that angle
    /// increases through the value (mod 2 pi).
    #[arg(long, value_name = "NAME=VALUE")]
    pub section: Option<String>,
    #[command(flatten)]
    pub end: EndArg,
    #[command(flatten)]
    pub stepping: MethodArgs,
    /// Relative and absolute tolerance of adaptive methods, 1e-15 (round-off) to 1.
    #[arg(long, value_name = "X", allow_hyphen_values = true)]
    pub tol: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

/// What poincare runs without arguments.
pub const DEFAULTS: Defaults = crate::args::Defaults::of(
    &pendula::study::defaults::POINCARE,
    &[
        ("system", "The double pendulum, or the chain with --set links=2."),
        (
            "method",
            "dop853 or dopri5 (adaptive, dense output) or any fixed-step method with --dt (gauss-legendre-4: symplectic).",
        ),
        ("dt", "Required by fixed-step methods; given, every method takes fixed steps of it."),
        ("t_end", "The length of each orbit."),
    ],
);

/// The files it writes in its study directory (listed with the command in `cli::COMMANDS`).
pub const FILES: &[&str] = &["poincare.csv", "poincare.png", "poincare.svg"];

pub fn run(args: &PoincareArgs) -> Result<()> {
    let system = args.system.name(&DEFAULTS);
    let values = study::values(system, &args.common.set.items)?;
    let info = values.info();
    let state: Vec<&str> = info.state.iter().map(|q| q.name).collect();
    refuse_settings(
        &args.common.set.items,
        &state,
        "poincare starts every orbit on the section at the energy --energy; set parameters only",
    )?;
    let model = values.build();
    // The system first: a section of a system without an energy surface is no question of
    // which section.
    pendula::analysis::poincare::check_system(&*model)?;
    let energy = DEFAULTS.number("energy", &args.energy, "an energy in J")?;
    // The energy's domain before the work it implies: a huge energy is no question of cost.
    let most = pendula::analysis::poincare::max_energy(&*model);
    if energy > most {
        bail!(
            "invalid --energy {}: at most {} here, 10^12 energy scales above the energy at rest (beyond it the potential energy is lost in the kinetic energy's round-off)",
            clip(args.energy.as_deref().unwrap_or_default()),
            with_unit(number(most), info.energy_unit())
        );
    }
    let count = match &args.count {
        Some(t) => parse_count("--count", t, 1, limits::MAX_ORBITS, "orbits")? as usize,
        None => DEFAULTS.of.count("count") as usize,
    };
    let section_text = args.section.as_deref().unwrap_or(DEFAULTS.of.text("section"));
    let (name, value) = section_text.split_once('=').ok_or_else(|| {
        anyhow::anyhow!("invalid --section `{}`: expected NAME=VALUE, e.g. theta1=0", clip(section_text))
    })?;
    let name = name.trim();
    let angles: Vec<&str> = info.state.iter().filter(|q| q.is_angle()).map(|q| q.name).collect();
    let Some(section) = info.state.iter().position(|q| q.name == name && q.is_angle()) else {
        bail!(
            "invalid --section `{}`: `{}` is not an angle of {system}{}; valid: {}",
            clip(section_text),
            clip(name),
            did_you_mean(&suggestions(name, angles.iter().copied())),
            angles.join(", ")
        );
    };
    let value = parse_value(name, value, Some(&info.state[section]))?;
    let t_end = args.end.positive_t_end(&DEFAULTS)?;
    let method = args.stepping.method(&DEFAULTS)?;
    let stepping = match (&args.stepping.dt, method.scheme) {
        (Some(text), _) => {
            let h = parse_float("--dt", text, "a step size in seconds")?;
            if !(h > 0.0 && h <= t_end) {
                bail!("invalid --dt {}: must be finite, > 0 and at most --t-end", clip(text));
            }
            Stepping::Fixed(h)
        }
        (None, Scheme::Embedded(_)) => {
            let tol = DEFAULTS.number("tol", &args.tol, "a tolerance")?;
            let tol = Tolerances { rtol: tol, atol: tol, h_min: 0.0, h_max: f64::INFINITY };
            tol.validate()
                .map_err(|e| crate::parse::flag_error(e, &[("rtol", "--tol"), ("atol", "--tol")]))?;
            Stepping::Adaptive(tol)
        }
        (None, _) => bail!("--method {} takes fixed steps: give --dt", method.name),
    };
    // What it costs: every orbit's steps. Adaptive steps follow the motion: at an energy K
    // above the potential's minimum, the motion is faster than small oscillations by about
    // sqrt(K / scale) (scale: the system's energy scale at rest).
    let rest = vec![0.0; info.state.len()];
    let scale = model.energy_scale(&rest);
    let kinetic = (energy - model.energy(0.0, &rest)).max(scale);
    let period = model.time_scale() * (scale / kinetic).sqrt();
    let (steps, how) = match stepping {
        Stepping::Fixed(h) => (limits::steps(t_end, h), format!("steps of {} s", pendula::error::Short(h))),
        Stepping::Adaptive(_) => (
            limits::adaptive_steps(t_end, period, f64::INFINITY),
            format!(
                "adaptive steps, at least {} per period of {} s",
                limits::ADAPTIVE_STEPS_PER_PERIOD,
                pendula::error::Short(period)
            ),
        ),
    };
    let crossings = count as f64 * (t_end / period).max(1.0);
    limits::check(
        "poincare",
        args.common.large.allow_large,
        &[
            Estimate::new(
                Cost::Steps,
                count as f64 * steps,
                format!("{count} orbits x {} {how}", limits::round(steps)),
            ),
            // About one crossing per period, and its CSV row, kept until written.
            Estimate::new(
                Cost::Output,
                crossings * 6.0 * limits::CSV_BYTES_PER_VALUE,
                format!("about {} crossings", limits::round(crossings)),
            ),
        ],
    )?;
    let spec = PoincareSpec { energy, count, section, value, t_end };
    // The outputs before the work: a path that cannot be written fails first.
    let mut out = OutDir::new(args.common.out_dir.as_deref(), "poincare", FILES)?;
    let summary = args.common.summary.open()?;
    let orbits = poincare(&*model, method, stepping, &spec)?;

    let other = 1 - section;
    let (q_name, p_name) = (info.state[other].name, format!("p{}", &info.state[other].name[5..]));
    let mut rows = Vec::new();
    let worst_energy = pendula::analysis::poincare::max_energy_error(&*model, &orbits, energy);
    let mut fig = Figure::new(
        format!(
            "{system}: Poincaré section {} = {} rad (rising), E = {}, {count} orbits ({})",
            pretty(name),
            number(value),
            with_unit(number(energy), info.energy_unit()),
            method.name
        ),
        axis_label(q_name, "rad"),
        axis_label(&p_name, if info.dimensionless { "1" } else { "kg m^2/s" }),
    )
    .scales(Scale::Linear, Scale::Linear);
    let mut total = 0;
    for (k, orbit) in orbits.iter().enumerate() {
        let mut points = Vec::with_capacity(orbit.crossings.len());
        for (t, z) in orbit.t.iter().zip(&orbit.crossings) {
            let (q, p) = (pendula::system::wrap_angle(z[other]), z[2 + other]);
            rows.push(vec![k.to_string(), num(*t), num(q), num(p), num(z[section]), num(z[2 + section])]);
            points.push((q, p));
        }
        total += points.len();
        // Colour tells orbits apart; with tens of them a legend would hide the section.
        fig = fig.with("", palette(k), Kind::Dots, points);
    }
    if total == 0 {
        bail!("no orbit crossed the section in {t_end} s: raise --t-end or change --energy");
    }
    let p_section = format!("p{}", &name[5..]);
    out.csv("poincare.csv", &["orbit", "t", q_name, &p_name, name, &p_section], &rows)?;
    out.figure("poincare", &fig)?;
    sayln!(
        summary,
        "{system}: {count} orbits at E = {}, {total} crossings of {name} = {value} (rising) in {}; max |H - E| at crossings {}",
        with_unit(energy, info.energy_unit()),
        with_unit(t_end, info.time_unit()),
        with_unit(format!("{worst_energy:.2e}"), info.energy_unit())
    );
    // The summary and the files appear together or not at all.
    out.finish_with(
        summary,
        &json!({
            "system": system, "method": method.name, "energy": energy, "count": count,
            "section": {"name": name, "value": value, "direction": "rising"},
            "t_end": t_end, "crossings": total,
            "crossings_per_orbit": orbits.iter().map(|o| o.t.len()).collect::<Vec<_>>(),
            "max_energy_error": worst_energy,
        }),
    )?;
    Ok(())
}
