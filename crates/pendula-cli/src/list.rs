//! `pendula list systems|methods|presets`: everything read from the library's registries.

use std::io::Write;

use anyhow::Result;
use clap::ValueEnum;
use pendula::integrator::METHODS;
use pendula::model::CATALOGUE;
use pendula::system::Quantity;

/// What `pendula list` lists.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum ListWhat {
    Systems,
    Methods,
    Presets,
}

fn show_default(q: &Quantity) -> String {
    if q.is_angle() && q.default != 0.0 {
        format!("{} ({}deg)", q.default, (q.default.to_degrees() * 1e9).round() / 1e9)
    } else {
        format!("{}", q.default)
    }
}

pub fn run(what: ListWhat) -> Result<()> {
    let mut out = std::io::stdout().lock();
    match what {
        ListWhat::Systems => {
            for (i, s) in CATALOGUE.iter().enumerate() {
                if i > 0 {
                    writeln!(out)?;
                }
                writeln!(out, "{}  {}", s.name, s.description)?;
                for (title, list) in [("parameters", s.parameters), ("state", s.state)] {
                    writeln!(out, "  {title}:")?;
                    for q in list {
                        writeln!(
                            out,
                            "    {:<16} {:<8} default {:<26} {}",
                            q.name,
                            q.unit,
                            show_default(q),
                            q.description
                        )?;
                    }
                }
            }
        }
        ListWhat::Presets => {
            for p in pendula::system::driven::PRESETS {
                let settings: Vec<String> = p.settings.iter().map(|(n, v)| format!("{n}={v}")).collect();
                writeln!(out, "{:<26} {:<16} {}", p.name, p.system, settings.join(" "))?;
                writeln!(out, "{:<26} {}", "", p.description)?;
                writeln!(out, "{:<26} source: {}", "", p.source)?;
            }
        }
        ListWhat::Methods => {
            writeln!(
                out,
                "{:<17} {:>5}  {:<10} {:<9} requirement",
                "method", "order", "symplectic", "symmetric"
            )?;
            for m in METHODS {
                writeln!(
                    out,
                    "{:<17} {:>5}  {:<10} {:<9} {}",
                    m.name,
                    m.order,
                    if m.symplectic { "yes" } else { "no" },
                    if m.symmetric { "yes" } else { "no" },
                    m.requirement.describe()
                )?;
                writeln!(out, "{:<17} {}", "", m.description)?;
                writeln!(out, "{:<17} ref: {}", "", m.reference)?;
            }
        }
    }
    Ok(())
}
