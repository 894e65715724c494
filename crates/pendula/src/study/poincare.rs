//! `poincare`: a Poincaré section of a conservative two-degree-of-freedom system (the double
//! pendulum by default; [`mod@crate::analysis::poincare`]): orbits started on one energy
//! surface, their crossings of θₛ = v (mod 2π) with θ̇ₛ > 0 located by events, as a scatter
//! of the other angle and its momentum coloured by orbit.

use super::prelude::*;
use crate::Error;
use crate::analysis::poincare::{self as section_of, PoincareSpec, Stepping};
use crate::control::Tolerances;
use crate::error::{Short, approx};
use crate::integrator::Scheme;

/// The study's entry in [`super::STUDIES`].
pub const STUDY: Study = Study {
    name: "poincare",
    about: "A Poincaré section: orbits on one energy surface and their crossings of a section, located by events",
    params: &[
        Param::system_parameters(
            "double",
            "poincare starts every orbit on the section at the energy `energy`",
        ),
        Param {
            name: "energy",
            help: "The energy of every orbit (regular and chaotic orbits side by side on the default)",
            kind: Kind::Real { default: -15.0, unit: Unit::Fixed("J"), domain: Domain::Finite },
        },
        Param {
            name: "count",
            help: "The number of orbits",
            kind: Kind::Count { default: 30, min: 1, max: 10_000, of: "orbits" },
        },
        Param {
            name: "section",
            help: "The section, an angle and its value NAME=VALUE (rad); a crossing counts when that angle increases through the value (mod 2π)",
            kind: Kind::Section { default: "theta1=0" },
        },
        Param::time("t_end", "The length of each orbit", 300.0),
        Param {
            name: "method",
            help: "dop853 or dopri5 (adaptive, dense output), or any fixed-step method with `dt` (gauss-legendre-4: symplectic)",
            kind: Kind::Method { default: "dop853" },
        },
        Param {
            name: "dt",
            help: "Fixed steps of this size, for any method (a fixed-step method needs it)",
            kind: Kind::Optional {
                unit: Unit::Time,
                domain: Domain::Positive,
                none: "adaptive steps at `tol`",
            },
        },
        Param {
            name: "tol",
            help: "The relative and absolute tolerance of adaptive steps, 1e-15 (round-off) to 1",
            kind: Kind::Real { default: 1e-10, unit: Unit::None, domain: Domain::Positive },
        },
    ],
    files: &["poincare", "orbits"],
    run,
};

/// The momenta's names, by the index of their angle.
const MOMENTA: [&str; 2] = ["p1", "p2"];

fn run(inputs: &Inputs, budget: &Budget) -> Result<Report, Error> {
    let args = Args::new(&STUDY, inputs)?;
    let values = args.system("system")?;
    let info = values.info();
    let model = values.build();
    // The system first: a section of a system without an energy surface is no question of
    // which section.
    section_of::check_system(&*model)?;
    let energy = args.real("energy")?;
    // The energy's domain before the work it implies: a huge energy is no question of cost.
    let most = section_of::max_energy(&*model);
    if energy > most {
        return Err(Error::InvalidInput {
            name: "energy".into(),
            value: Short(energy).to_string(),
            allowed: format!(
                "at most {} {} here, 10^12 energy scales above the energy at rest (beyond it the potential energy is lost in the kinetic energy's round-off)",
                sig(most),
                info.energy_unit()
            ),
        });
    }
    let count = args.count("count")? as usize;
    let (section, value) = args.section("section", info)?;
    let t_end = args.real("t_end")?;
    let method = args.method("method")?;
    let stepping = match (args.optional("dt")?, method.scheme) {
        (Some(h), _) if h > t_end => {
            return Err(Error::InvalidValue {
                name: "dt".into(),
                value: h,
                allowed: "must be finite, > 0 and at most `t_end`",
            });
        }
        (Some(h), _) => Stepping::Fixed(h),
        (None, Scheme::Embedded(_)) => {
            let tol = args.real("tol")?;
            let tol = Tolerances { rtol: tol, atol: tol, h_min: 0.0, h_max: f64::INFINITY };
            tol.validate().map_err(|e| match e {
                Error::InvalidValue { value, allowed, .. } => {
                    Error::InvalidValue { name: "tol".into(), value, allowed }
                }
                e => e,
            })?;
            Stepping::Adaptive(tol)
        }
        (None, _) => {
            return Err(Error::InvalidInput {
                name: "method".into(),
                value: method.name.into(),
                allowed: "takes fixed steps: give `dt`".into(),
            });
        }
    };
    // What it costs: every orbit's steps. Adaptive steps follow the motion: at an energy K
    // above the potential's minimum, the motion is faster than small oscillations by about
    // sqrt(K / scale) (scale: the system's energy scale at rest).
    let rest = vec![0.0; info.state.len()];
    let scale = model.energy_scale(&rest);
    let kinetic = (energy - model.energy(0.0, &rest)).max(scale);
    let period = model.time_scale() * (scale / kinetic).sqrt();
    let (steps, how) = match stepping {
        Stepping::Fixed(h) => ((t_end / h).ceil().max(1.0), format!("steps of {} s", Short(h))),
        Stepping::Adaptive(_) => (
            super::adaptive_steps(t_end, period, f64::INFINITY),
            format!(
                "adaptive steps, at least {} per period of {} s",
                super::ADAPTIVE_STEPS_PER_PERIOD,
                Short(period)
            ),
        ),
    };
    budget.afford(count as f64 * steps, format!("{count} orbits x {} {how}", approx(steps)))?;
    // About one crossing per period, each a row of six values, kept until written.
    let crossings = count as f64 * (t_end / period).max(1.0);
    budget.afford_values(crossings * 6.0, format!("about {} crossings", approx(crossings)))?;

    let spec = PoincareSpec { energy, count, section, value, t_end };
    let orbits = section_of::poincare(&*model, method, stepping, &spec)?;
    let total: usize = orbits.iter().map(|o| o.t.len()).sum();
    if total == 0 {
        return Err(Error::InvalidInput {
            name: "t_end".into(),
            value: Short(t_end).to_string(),
            allowed: format!(
                "no orbit crossed the section in {}{}: raise `t_end` or change `energy`",
                Short(t_end),
                unit_suffix(info.time_unit())
            ),
        });
    }
    let worst = section_of::max_energy_error(&*model, &orbits, energy);

    let other = 1 - section;
    let (name, q_name) = (info.state[section].name, info.state[other].name);
    let mut columns: [Vec<f64>; 6] = Default::default();
    let mut series = Vec::new();
    for (k, orbit) in orbits.iter().enumerate() {
        let mut points = Vec::with_capacity(orbit.crossings.len());
        for (t, z) in orbit.t.iter().zip(&orbit.crossings) {
            let (q, p) = (crate::system::wrap_angle(z[other]), z[2 + other]);
            for (column, v) in columns.iter_mut().zip([k as f64, *t, q, p, z[section], z[2 + section]]) {
                column.push(v);
            }
            points.push([q, p]);
        }
        series.push(Line::new(format!("orbit {k}"), Style::Dots, points));
    }
    let (eu, tu) = (info.energy_unit(), info.time_unit());
    let momentum = if info.dimensionless { "" } else { "kg m^2/s" };
    let [orbit, t, q, p, qs, ps] = columns;
    let crossings_table = Table {
        name: "poincare",
        shown: false,
        columns: vec![
            Column::whole("orbit", orbit),
            Column::numbers("t", tu, t),
            Column::numbers(q_name, "rad", q),
            Column::numbers(MOMENTA[other], momentum, p),
            Column::numbers(name, "rad", qs),
            Column::numbers(MOMENTA[section], momentum, ps),
        ],
    };
    let mut starts: Vec<Vec<f64>> = vec![Vec::new(); info.state.len()];
    for o in &orbits {
        for (column, v) in starts.iter_mut().zip(&o.initial) {
            column.push(*v);
        }
    }
    let mut orbit_columns = vec![
        Column::whole("orbit", (0..orbits.len()).map(|k| k as f64).collect()),
        Column::whole("crossings", orbits.iter().map(|o| o.t.len() as f64).collect()),
    ];
    for (q, column) in info.state.iter().zip(starts) {
        orbit_columns.push(Column::numbers(q.name, q.unit, column));
    }
    // Colour tells orbits apart; with tens of them a legend would hide the section.
    let plot = Plot {
        legend: false,
        ..Plot::lines(
            "poincare",
            format!(
                "{}: Poincaré section {} = {} rad (rising), E = {}{}, {count} orbits ({})",
                info.name,
                name,
                Short(value),
                Short(energy),
                unit_suffix(eu),
                method.name
            ),
            Axis { label: q_name.into(), unit: "rad".into(), log: false },
            Axis {
                label: MOMENTA[other].into(),
                unit: if momentum.is_empty() { "1" } else { momentum }.into(),
                log: false,
            },
            series,
        )
    };
    let summary = vec![format!(
        "{}: {count} orbits at E = {}{}, {total} crossings of {name} = {} (rising) in {}{}; max |H - E| at crossings {worst:.2e}{}",
        info.name,
        Short(energy),
        unit_suffix(eu),
        Short(value),
        Short(t_end),
        unit_suffix(tu),
        unit_suffix(eu)
    )];
    let mut report_inputs = vec![
        ("system", Input::Name(info.name.into())),
        ("energy", Input::Number(energy)),
        ("count", Input::Number(count as f64)),
        ("section", Input::Name(format!("{name}={}", Short(value)))),
        ("t_end", Input::Number(t_end)),
        ("method", Input::Name(method.name.into())),
    ];
    match stepping {
        Stepping::Fixed(h) => {
            report_inputs.extend([("dt", Input::Number(h)), ("tol", Input::Name("none".into()))])
        }
        Stepping::Adaptive(tol) => {
            report_inputs.extend([("dt", Input::Name("none".into())), ("tol", Input::Number(tol.rtol))]);
        }
    }
    Ok(Report {
        study: STUDY.name,
        inputs: report_inputs,
        summary,
        numbers: vec![
            Number { key: "crossings", value: total as f64, unit: "", about: "the crossings of the section" },
            Number {
                key: "max_energy_error",
                value: worst,
                unit: eu,
                about: "the largest |H − E| at a crossing",
            },
        ],
        texts: Vec::new(),
        tables: vec![crossings_table, Table { name: "orbits", shown: false, columns: orbit_columns }],
        plots: vec![plot],
    })
}
