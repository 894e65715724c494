//! `bifurcation`: a stroboscopic orbit diagram ([`crate::analysis::strobe::orbit_diagram`]) —
//! the state once per drive period after a transient, against a swept parameter. The
//! damped, driven pendulum runs on the ensemble engine's SIMD lanes
//! ([`crate::ensemble::driven`]); other driven systems run the scalar RK4 per parameter
//! value, in parallel. Either way the result does not depend on the thread count.

use std::time::Instant;

use super::prelude::*;
use crate::Error;
use crate::analysis::strobe::{OrbitDiagramSpec, orbit_diagram};
use crate::error::{Short, approx};

/// The study's entry in [`super::STUDIES`].
pub const STUDY: Study = Study {
    name: "bifurcation",
    about: "A stroboscopic orbit diagram of a driven system against a swept parameter",
    params: &[
        Param::system("driven-pendulum", &[]),
        Param::preset(),
        Param {
            name: "param",
            help: "The swept parameter, NAME=LO:HI:N: N cell centres of [LO, HI], as a sweep's axis",
            kind: Kind::Axis { default: Some(("driven-pendulum", "drive_amplitude=1.0:1.5:800")) },
        },
        Param {
            name: "transient",
            help: "Time discarded before sampling, rounded up to whole drive periods",
            kind: Kind::Real { default: 1000.0, unit: Unit::Time, domain: Domain::NonNegative },
        },
        Param {
            name: "samples",
            help: "Samples (drive periods) per parameter value",
            kind: Kind::Count { default: 150, min: 1, max: 1_000_000, of: "samples" },
        },
        Param {
            name: "steps_per_period",
            help: "RK4 steps per drive period",
            kind: Kind::Count { default: 100, min: 4, max: 1_000_000, of: "steps" },
        },
        Param {
            name: "variable",
            help: "The state variable plotted against the parameter",
            kind: Kind::Variable { velocity: true },
        },
        Param { name: "threads", help: "The threads it runs on", kind: Kind::Threads },
    ],
    files: &["bifurcation", "run"],
    run,
};

fn run(inputs: &Inputs, budget: &Budget) -> Result<Report, Error> {
    let args = Args::new(&STUDY, inputs)?;
    let values = args.system("system")?;
    let info = values.info();
    if info.quantity("drive_frequency").is_err() {
        return Err(Error::InvalidInput {
            name: "system".into(),
            value: info.name.into(),
            allowed: "bifurcation needs a driven system (a drive_frequency parameter)".into(),
        });
    }
    let axis = args.axis("param", info)?;
    if let Some((q, v)) = inputs.set.iter().find(|(q, _)| *q == axis.name) {
        return Err(Error::InvalidInput {
            name: "set".into(),
            value: format!("{q}={}", Short(*v)),
            allowed: format!(
                "`{q}` is both set and swept: `set` {q}={} and `param` {q}={}:{}:{}; give one",
                Short(*v),
                Short(axis.lo),
                Short(axis.hi),
                axis.n
            ),
        });
    }
    let transient = args.real("transient")?;
    let samples = args.count("samples")? as usize;
    let m = args.count("steps_per_period")? as u32;
    let dim = info.state.len();
    let variable = args.variable("variable", info)?;
    let threads = args.threads("threads")?;
    // One value's parameters, validated (a start whose energy overflows refused here, before
    // its cost is estimated).
    let base: Vec<(String, f64)> =
        info.quantities().map(|q| (q.name.to_owned(), values.get(q.name))).collect();
    let value = |i: usize| {
        let mut s = base.clone();
        s.push((axis.name.clone(), axis.centre(i)));
        let v = info.values(&s)?;
        v.check_energy().map(|()| v)
    };
    // What it costs, before the values are made: every value's transient and samples, at the
    // fastest drive along the axis (its most periods), and the samples' table.
    // Orbit diagrams run RK4 on the engine's lanes wherever the engine runs the system.
    let simd = {
        let crate::integrator::Scheme::ExplicitRk(rk4) = crate::integrator::explicit_rk::RK4.scheme else {
            unreachable!("RK4 is explicit")
        };
        crate::ensemble::engine::supports(info, &crate::ensemble::engine::LaneMethod::Rk(rk4))
    };
    let w = value(0)?.get("drive_frequency").max(value(axis.n - 1)?.get("drive_frequency"));
    let periods = (transient * w / (2.0 * std::f64::consts::PI)).ceil() + samples as f64;
    let n = axis.n as f64;
    let what = format!("{} values x {} drive periods x {m} steps", approx(n), approx(periods));
    if simd {
        budget.afford_lanes(n * periods * f64::from(m), what)?;
    } else {
        budget.afford(n * periods * f64::from(m), what)?;
    }
    let rows = n * samples as f64;
    budget.afford_values(rows * (2 + dim) as f64, format!("{} rows", approx(rows)))?;
    let all: Vec<crate::system::Values> = (0..axis.n).map(value).collect::<Result<_, _>>()?;
    if let Some(v) = all.iter().find(|v| v.get("drive_frequency") <= 0.0) {
        return Err(Error::InvalidValue {
            name: "drive_frequency".into(),
            value: v.get("drive_frequency"),
            allowed: "a stroboscopic diagram needs a drive (set drive_frequency > 0)",
        });
    }

    let begin = Instant::now();
    let spec = OrbitDiagramSpec { transient, samples, steps_per_period: m };
    let diagram = || orbit_diagram(&all, &spec);
    let data = match threads {
        Some(t) => rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .map_err(|e| Error::InvalidInput {
                name: "threads".into(),
                value: t.to_string(),
                allowed: format!("threads the system can start ({e})"),
            })?
            .install(diagram),
        None => diagram(),
    }
    .map_err(|e| match e {
        // Which value failed, in the parameter's name.
        Error::NonFiniteMember { member, t } => {
            Error::NonFiniteIn { place: format!("{} = {}", axis.name, Short(axis.centre(member))), t }
        }
        other => other,
    })?;
    let wall = begin.elapsed().as_secs_f64();
    let used = threads.unwrap_or_else(rayon::current_num_threads);

    let mut columns: Vec<Vec<f64>> = vec![Vec::with_capacity(axis.n * samples); 2 + dim];
    let mut points = Vec::with_capacity(axis.n * samples);
    for (i, chunk) in data.chunks_exact(samples * dim).enumerate() {
        let p = axis.centre(i);
        for (s, y) in chunk.chunks_exact(dim).enumerate() {
            columns[0].push(p);
            columns[1].push(s as f64);
            for (c, v) in columns[2..].iter_mut().zip(y) {
                c.push(*v);
            }
            points.push([p, y[variable]]);
        }
    }
    let q = info.quantity(&axis.name)?;
    let mut table =
        vec![Column::numbers(q.name, q.unit, columns.remove(0)), Column::whole("sample", columns.remove(0))];
    for (q, c) in info.state.iter().zip(columns) {
        table.push(Column::numbers(q.name, q.unit, c));
    }
    let tu = info.time_unit();
    let kernel = if simd { "simd lanes (ensemble engine)" } else { "scalar, per value" };
    let state = &info.state[variable];
    let plot = Plot {
        system: Some(info.name),
        legend: false,
        ..Plot::lines(
            "bifurcation",
            format!(
                "{}: {samples} samples per value after t = {}{} (RK4, {m} steps/period)",
                info.name,
                Short(transient),
                unit_suffix(tu)
            ),
            Axis { label: q.name.into(), unit: q.unit.into(), log: false },
            Axis { label: format!("{} at drive phase 0", state.name), unit: state.unit.into(), log: false },
            vec![Line::new("orbit diagram", Style::Dots, points)],
        )
    };
    let summary = vec![format!(
        "{}: {} values of {} in [{}, {}], {samples} samples each after t = {}{}; {kernel} [{wall:.2} s, {used} threads]",
        info.name,
        axis.n,
        axis.name,
        Short(axis.lo),
        Short(axis.hi),
        Short(transient),
        unit_suffix(tu),
    )];
    Ok(Report {
        study: STUDY.name,
        inputs: vec![
            ("system", Input::Name(info.name.into())),
            ("preset", Input::Name(args.preset("preset")?.unwrap_or("none").into())),
            ("param", Input::Name(format!("{}={}:{}:{}", axis.name, Short(axis.lo), Short(axis.hi), axis.n))),
            ("transient", Input::Number(transient)),
            ("samples", Input::Number(samples as f64)),
            ("steps_per_period", Input::Number(f64::from(m))),
            ("variable", Input::Name(state.name.into())),
            ("threads", Input::Number(used as f64)),
        ],
        summary,
        numbers: vec![
            Number { key: "lo", value: axis.lo, unit: q.unit, about: "the swept range's lower edge" },
            Number { key: "hi", value: axis.hi, unit: q.unit, about: "the swept range's upper edge" },
            Number { key: "n", value: n, unit: "", about: "the parameter's values" },
            Number { key: "wall_s", value: wall, unit: "s", about: "the wall-clock time it took" },
        ],
        texts: Vec::new(),
        tables: vec![
            Table { name: "bifurcation", shown: false, columns: table },
            Table {
                name: "run",
                shown: true,
                columns: vec![Column::text("kernel", vec![kernel.to_owned()])],
            },
        ],
        plots: vec![plot],
    })
}
