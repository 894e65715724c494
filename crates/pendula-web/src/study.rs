//! The library's studies ([`pendula::study::STUDIES`]) in the lab: `hello` lists them with
//! their parameters (the page builds a form from the list), and the `study` command runs
//! one within [`crate::Limits::max_study_steps`] (and `max_study_values`) and answers with its report — summary,
//! numbers, tables and its plots drawn by pendula-viz as PNG, the same figures the CLI
//! writes. A study added to the library appears in the lab with no code here.

use std::collections::BTreeMap;

use base64::Engine as _;
use pendula::study::{self, Budget, Cells, Input, Inputs, Kind, Unit};
use serde::Deserialize;
use serde_json::{Value, json};

use crate::config::Refusal;

/// The `study` command: a study's name, its inputs by parameter name (numbers, or names for
/// a system or a method), and settings of the system's parameters and start state.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyRequest {
    name: String,
    #[serde(default)]
    inputs: BTreeMap<String, Value>,
    #[serde(default)]
    set: BTreeMap<String, f64>,
}

/// The studies for `hello`: name, about, and each parameter's name, help, kind, default
/// (as documentation shows it), unit and the names it may take (a preset's).
pub fn list() -> Value {
    let studies: Vec<Value> = study::STUDIES
        .iter()
        .map(|s| {
            let params: Vec<Value> = s
                .params
                .iter()
                .map(|p| {
                    let unit = match p.real_unit() {
                        Some(Unit::Time) => "time",
                        Some(Unit::Fixed(u)) => u,
                        _ => "",
                    };
                    // `fixed-system` (the one system it runs) gets no field in the form.
                    let kind = p.kind_name();
                    // A preset is chosen from the catalogue's list.
                    let choices: Vec<&str> = match p.kind {
                        Kind::Preset => pendula::system::driven::PRESETS.iter().map(|p| p.name).collect(),
                        _ => Vec::new(),
                    };
                    json!({"name": p.name, "help": p.help, "kind": kind, "default": p.default_text(), "unit": unit, "choices": choices})
                })
                .collect();
            json!({"name": s.name, "about": s.about, "params": params})
        })
        .collect();
    Value::Array(studies)
}

/// Runs `request` within the study limits of `limits` and returns the `study` message.
///
/// # Errors
/// A [`Refusal`] with the library's message (bad input, a run over the limit, a failed run).
pub fn run(request: StudyRequest, limits: &crate::Limits) -> Result<Value, Refusal> {
    let spec = study::find(&request.name).map_err(|e| Refusal(e.to_string()))?;
    let mut inputs = Inputs { values: Vec::new(), set: request.set.into_iter().collect() };
    for (name, value) in request.inputs {
        let input = match value {
            Value::String(s) => Input::Name(s),
            Value::Number(n) => Input::Number(n.as_f64().unwrap_or(f64::NAN)),
            Value::Bool(b) => Input::Flag(b),
            // A list of numbers (the steps of a convergence study).
            Value::Array(items) if items.iter().all(Value::is_number) => {
                Input::Numbers(items.iter().filter_map(Value::as_f64).collect())
            }
            other => {
                return Err(Refusal(format!(
                    "invalid value {other} for `{name}`: a number or a name, a list of numbers, or true or false for a switch"
                )));
            }
        };
        inputs.values.push((name, input));
    }
    let budget = Budget {
        max_steps: Some(limits.max_study_steps as f64),
        max_values: Some(limits.max_study_values as f64),
        // The lanes run each system about ten times faster than the scalar integrators.
        max_lane_steps: Some(10.0 * limits.max_study_steps as f64),
    };
    let report = (spec.run)(&inputs, &budget).map_err(|e| Refusal(e.to_string()))?;
    let tables: Vec<Value> = report
        .tables
        .iter()
        .map(|t| {
            let columns: Vec<Value> = t
                .columns
                .iter()
                .map(|c| {
                    let values = match &c.values {
                        Cells::Numbers(v) => json!(v),
                        Cells::Text(t) => json!(t),
                    };
                    json!({"name": c.name, "unit": c.unit, "values": values})
                })
                .collect();
            json!({"name": t.name, "shown": t.shown, "columns": columns})
        })
        .collect();
    let mut plots = Vec::new();
    for p in &report.plots {
        let png = pendula_viz::Figure::from(p).png().map_err(|e| Refusal(e.to_string()))?;
        plots.push(json!({
            "name": p.name, "title": p.title,
            "png": base64::engine::general_purpose::STANDARD.encode(png),
        }));
    }
    let numbers: Vec<Value> = report
        .numbers
        .iter()
        .map(|n| json!({"key": n.key, "value": n.value, "unit": n.unit, "about": n.about}))
        .collect();
    let texts: serde_json::Map<String, Value> =
        report.texts.iter().map(|(k, v)| ((*k).to_owned(), json!(v))).collect();
    let inputs: serde_json::Map<String, Value> = report
        .inputs
        .iter()
        .map(|(k, v)| {
            let v = match v {
                Input::Number(x) => json!(x),
                Input::Name(s) => json!(s),
                Input::Flag(b) => json!(b),
                Input::Numbers(v) => json!(v),
            };
            ((*k).to_owned(), v)
        })
        .collect();
    Ok(json!({
        "type": "study", "study": report.study, "inputs": inputs, "summary": report.summary,
        "numbers": numbers, "texts": texts, "tables": tables, "plots": plots,
    }))
}
