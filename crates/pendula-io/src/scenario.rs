//! Scenario files (`pendula simulate --scenario FILE`): TOML with the names of simulate's
//! flags, read by the CLI ([`read`], with limits on size and nesting and errors that point
//! at the line and column) and written by the lab ([`Scenario::to_toml`]), so that what the
//! lab offers is what the CLI reads.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::{Result, caused, invalid};

/// Bytes of a scenario file: a scenario is a few lines, and it is read whole.
pub const MAX_SCENARIO_BYTES: u64 = 1 << 20;
/// Nesting of arrays and tables in a scenario file (the parser recurses on it).
pub const MAX_SCENARIO_DEPTH: usize = 16;

/// A scenario file: the same names as `pendula simulate`'s flags, each optional (a flag
/// given overrides it).
#[derive(Debug, Default, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// The system's catalogue name.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub system: Option<String>,
    /// The method's name.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub method: Option<String>,
    /// The step, s (an adaptive method's first step).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt: Option<f64>,
    /// The end time, s.
    #[serde(alias = "t-end", skip_serializing_if = "Option::is_none")]
    pub t_end: Option<f64>,
    /// The number of steps (instead of `t_end`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steps: Option<u64>,
    /// Relative tolerance of an adaptive run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rtol: Option<f64>,
    /// Absolute tolerance of an adaptive run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub atol: Option<f64>,
    /// The smallest step of an adaptive run, s.
    #[serde(alias = "h-min", skip_serializing_if = "Option::is_none")]
    pub h_min: Option<f64>,
    /// The largest step of an adaptive run, s.
    #[serde(alias = "h-max", skip_serializing_if = "Option::is_none")]
    pub h_max: Option<f64>,
    /// Write every n-th step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub every: Option<u64>,
    /// The trajectory file.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub out: Option<PathBuf>,
    /// The JSON summary file.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub summary: Option<PathBuf>,
    /// Parameters and initial-state variables by name: numbers (SI units, radians) or
    /// strings in the value syntax (`"120deg"`, [`crate::value::parse_value`]).
    #[serde(default)]
    pub set: BTreeMap<String, toml::Value>,
}

impl Scenario {
    /// The scenario as a file's text, the keys given in the order above and `[set]` last.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a scenario serialises")
    }
}

/// Reads the scenario file at `path` ([`parse`]).
pub fn read(path: &Path) -> Result<Scenario> {
    use std::io::Read;
    let name = path.display();
    let cannot = |e: std::io::Error| caused(format!("cannot read scenario file {name}"), &e);
    let file = std::fs::File::open(path).map_err(cannot)?;
    // Read at most one byte past the cap: a huge file, or an endless one (/dev/zero, a
    // pipe), is refused without being read whole.
    let mut bytes = Vec::new();
    file.take(MAX_SCENARIO_BYTES + 1).read_to_end(&mut bytes).map_err(cannot)?;
    parse(bytes, &name.to_string())
}

/// The scenario in `bytes`, the contents of the file `name`: checked for its size, UTF-8 and
/// nesting before the TOML parser sees it; `t_end` and `steps` are not both set.
pub fn parse(bytes: Vec<u8>, name: &str) -> Result<Scenario> {
    if bytes.len() as u64 > MAX_SCENARIO_BYTES {
        return Err(invalid!(
            "scenario file {name} is larger than {}, the limit for a scenario (a few lines of keys and values)",
            crate::value::bytes(MAX_SCENARIO_BYTES as f64)
        ));
    }
    let text = String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let (line, column) = line_column(&String::from_utf8_lossy(e.as_bytes()), at);
        invalid!("invalid scenario file {name}, line {line}, column {column}: not UTF-8 text")
    })?;
    // The parser recurses on nested arrays and inline tables: a deep nest is refused first.
    if let Some(at) = too_deep(&text, MAX_SCENARIO_DEPTH) {
        let (line, column) = line_column(&text, at);
        return Err(invalid!(
            "invalid scenario file {name}, line {line}, column {column}: arrays or tables nested more than {} deep",
            MAX_SCENARIO_DEPTH
        ));
    }
    let scenario: Scenario = toml::from_str(&text).map_err(|e| {
        // toml's own message quotes the whole offending line and serde's may quote a whole
        // value: the message is clipped and the line shown around the error only.
        let message = clip_message(e.message());
        match e.span() {
            Some(span) => {
                let (line, column) = line_column(&text, span.start);
                let excerpt = excerpt(&text, span.start);
                invalid!("invalid scenario file {name}, line {line}, column {column}: {message}\n  {excerpt}")
            }
            None => invalid!("invalid scenario file {name}: {message}"),
        }
    })?;
    if scenario.t_end.is_some() && scenario.steps.is_some() {
        return Err(invalid!("scenario file {name} sets both t_end and steps; set one"));
    }
    Ok(scenario)
}

/// The 1-based line and column (in characters) of byte `at` of `text`.
fn line_column(text: &str, at: usize) -> (usize, usize) {
    let at = floor_boundary(text, at);
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[start..].chars().count() + 1)
}

/// The largest char boundary of `text` at or before `at`.
fn floor_boundary(text: &str, at: usize) -> usize {
    let mut at = at.min(text.len());
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    at
}

/// The line around byte `at`: at most 30 characters either side, marked where cut.
fn excerpt(text: &str, at: usize) -> String {
    const SIDE: usize = 30;
    let at = floor_boundary(text, at);
    let start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let end = text[at..].find('\n').map_or(text.len(), |i| at + i);
    let before: Vec<char> = text[start..at].chars().collect();
    let after: Vec<char> = text[at..end].chars().collect();
    let (b, a) = (before.len().saturating_sub(SIDE), after.len().min(SIDE));
    format!(
        "{}{}{}{}",
        if b > 0 { "…" } else { "" },
        before[b..].iter().collect::<String>(),
        after[..a].iter().collect::<String>(),
        if a < after.len() { "…" } else { "" }
    )
}

/// A parser's message, clipped to 200 characters and to its first line.
fn clip_message(message: &str) -> String {
    const KEEP: usize = 200;
    let first = message.lines().next().unwrap_or("");
    match first.char_indices().nth(KEEP) {
        None => first.to_owned(),
        Some((cut, _)) => format!("{}… (clipped)", &first[..cut]),
    }
}

/// The byte offset where arrays and inline tables of a TOML text first nest deeper than
/// `max`, if they do: brackets are counted outside strings and comments, in one pass.
fn too_deep(text: &str, max: usize) -> Option<usize> {
    let b = text.as_bytes();
    let (mut i, mut depth) = (0, 0usize);
    while i < b.len() {
        match b[i] {
            b'#' => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            q @ (b'"' | b'\'') => {
                let triple = b[i..].starts_with(if q == b'"' { b"\"\"\"" } else { b"\'\'\'" });
                let width = if triple { 3 } else { 1 };
                i += width;
                while i < b.len() {
                    if q == b'"' && b[i] == b'\\' {
                        i += 2;
                        continue;
                    }
                    if b[i] == q && (width == 1 || b[i..].starts_with(&[q, q, q])) {
                        i += width - 1;
                        break;
                    }
                    // A single-line string ends at the line's end, closed or not.
                    if width == 1 && b[i] == b'\n' {
                        break;
                    }
                    i += 1;
                }
            }
            b'[' | b'{' => {
                depth += 1;
                if depth > max {
                    return Some(i);
                }
            }
            b']' | b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
        i += 1;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nesting_is_counted_outside_strings_and_comments() {
        assert_eq!(too_deep("a = [[1, 2], [3]]\n", 2), None);
        assert_eq!(too_deep("a = [[[1]]]\n", 2), Some(6));
        assert_eq!(too_deep("a = \"[[[[\" # {{{{\nb = '[[[['\n", 2), None);
        assert_eq!(too_deep("a = \"\"\"\n[[[[\n\"\"\"\nb = '''{{{{'''\n", 2), None);
        assert_eq!(too_deep("a = \"\\\"[[[\"\n", 2), None);
        assert_eq!(too_deep("a = { b = { c = { d = 1 } } }\n", 2), Some(16));
    }

    #[test]
    fn a_written_scenario_reads_back() {
        let s = Scenario {
            system: Some("double".into()),
            method: Some("rk4".into()),
            dt: Some(0.001),
            t_end: Some(10.0),
            set: [
                ("theta1".to_owned(), toml::Value::Float(1.5)),
                ("links".to_owned(), toml::Value::Integer(3)),
            ]
            .into_iter()
            .collect(),
            ..Scenario::default()
        };
        let text = s.to_toml();
        assert_eq!(
            text,
            "system = \"double\"\nmethod = \"rk4\"\ndt = 0.001\nt_end = 10.0\n\n[set]\nlinks = 3\ntheta1 = 1.5\n"
        );
        assert_eq!(parse(text.into_bytes(), "s.toml").expect("a scenario"), s);
        let e = parse(b"t_end = 1\nsteps = 5\n".to_vec(), "s.toml").unwrap_err().to_string();
        assert_eq!(e, "scenario file s.toml sets both t_end and steps; set one");
        let e = parse(b"sytem = 1\n".to_vec(), "s.toml").unwrap_err().to_string();
        assert!(
            e.starts_with("invalid scenario file s.toml, line 1, column 1: unknown field `sytem`"),
            "{e}"
        );
    }
}
