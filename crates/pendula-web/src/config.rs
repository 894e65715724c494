//! A session's configuration: what the page asked for (system, parameters, start state,
//! method, step, mode), validated by the library before anything runs, and what the page is
//! told back (`config` message: the quantities with units and domains, how to draw the system,
//! the equivalent `pendula simulate` command and scenario file).

use pendula::integrator::{self, Method};
use pendula::model;
use pendula::system::{Domain, Quantity, SystemInfo, Values};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use crate::Limits;

/// How many pendulums a session runs, and how their starts differ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// One pendulum.
    Single,
    /// The same start run by 2–4 methods (the paper's lesson on energy, seen happening).
    Race,
    /// `count` pendulums of one method, the first angle `delta` apart from one to the next.
    Butterfly,
}

/// The `configure` command: every field optional, missing ones keep their current values.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Configure {
    pub system: Option<String>,
    #[serde(default)]
    pub params: serde_json::Map<String, Value>,
    #[serde(default)]
    pub state: serde_json::Map<String, Value>,
    pub method: Option<String>,
    pub dt: Option<f64>,
    pub mode: Option<Mode>,
    pub methods: Option<Vec<String>>,
    pub count: Option<usize>,
    pub delta: Option<f64>,
    pub speed: Option<f64>,
    pub poincare: Option<bool>,
}

/// A validated configuration. `settings` are the (name, value) pairs given over the
/// catalogue's defaults (parameters and start state), in the order given.
#[derive(Debug, Clone)]
pub struct Config {
    pub values: Values,
    pub settings: Vec<(String, f64)>,
    pub method: &'static Method,
    pub dt: f64,
    pub mode: Mode,
    pub methods: Vec<&'static Method>,
    pub count: usize,
    pub delta: f64,
    pub speed: f64,
    pub poincare: bool,
}

/// A refusal, in words the page shows as they are.
#[derive(Debug, Clone, PartialEq)]
pub struct Refusal(pub String);

impl From<pendula::Error> for Refusal {
    fn from(e: pendula::Error) -> Self {
        Refusal(e.to_string())
    }
}

fn refuse<T>(message: impl Into<String>) -> Result<T, Refusal> {
    Err(Refusal(message.into()))
}

/// The largest magnitude accepted for a start-state value: a pendulum spun at 10⁴ rad/s is
/// already far beyond anything the page can show, and larger values only overflow the energy.
pub const MAX_STATE: f64 = 1e4;
/// Step sizes accepted, in the system's unit of time.
pub const DT_RANGE: (f64, f64) = (1e-5, 0.5);
/// Speeds accepted, simulated seconds per wall second.
pub const SPEED_RANGE: (f64, f64) = (0.01, 1000.0);
/// The largest butterfly offset between neighbours, rad (larger is not "nearby").
pub const MAX_DELTA: f64 = 0.1;

impl Config {
    /// The start of every session: the library's default run
    /// ([`pendula::simulate::defaults`]: the free double pendulum, RK4 at 1 ms), at real
    /// time, so that the lab's first run is `pendula simulate`'s and `pendula.solve`'s.
    pub fn initial() -> Config {
        use pendula::simulate::defaults;
        let values =
            model::find(defaults::SYSTEM).expect("catalogued").values(&[]).expect("defaults are valid");
        let rk4 = integrator::find("rk4").expect("registered");
        Config {
            values,
            settings: Vec::new(),
            method: integrator::find(defaults::METHOD).expect("registered"),
            dt: defaults::DT,
            mode: Mode::Single,
            methods: vec![rk4, integrator::find("gauss-legendre-4").expect("registered")],
            count: 8,
            delta: 1e-9,
            speed: 1.0,
            poincare: false,
        }
    }

    /// The system's info (for the chain, the member its links pick).
    pub fn info(&self) -> &'static SystemInfo {
        self.values.info()
    }

    /// This configuration changed as `cmd` asks, validated; `self` is left as it was.
    pub fn apply(&self, cmd: &Configure, limits: &Limits) -> Result<(Config, Option<String>), Refusal> {
        let mut notice = None;
        let family = match &cmd.system {
            Some(name) => model::find(name)?,
            None => family_of(self.info()),
        };
        let same_system = std::ptr::eq(family, family_of(self.info()));
        let mut settings = if same_system { self.settings.clone() } else { Vec::new() };
        let number = |name: &str, v: &Value| -> Result<f64, Refusal> {
            v.as_f64().ok_or_else(|| Refusal(format!("{name} = {v}: a number is needed")))
        };
        for (name, v) in &cmd.params {
            let value = number(name, v)?;
            if !family.parameters.iter().any(|q| q.name == name) {
                let candidates = family.parameters.iter().map(|q| q.name);
                return Err(pendula::Error::unknown_name(family.name, name, candidates).into());
            }
            settings.push((name.clone(), value));
        }
        // The chain's links may have changed its state: start values of rods it no longer has
        // are dropped.
        let member = family.values(&settings)?.info();
        settings.retain(|(n, _)| member.quantities().any(|q| q.name == n));
        for (name, v) in &cmd.state {
            let value = number(name, v)?;
            if !member.state.iter().any(|q| q.name == name) {
                let candidates = member.state.iter().map(|q| q.name);
                return Err(pendula::Error::unknown_name(member.name, name, candidates).into());
            }
            if value.abs() > MAX_STATE {
                return refuse(format!("{name} = {value}: start values must be within ±{MAX_STATE}"));
            }
            settings.push((name.clone(), value));
        }
        settings = dedup(settings);
        let values = family.values(&settings)?;
        let built = values.build();
        let method = match &cmd.method {
            Some(name) => {
                let m = integrator::find(name)?;
                built.check(m)?;
                m
            }
            // A new system keeps the method when it applies; when not, the page is told.
            None => match built.check(self.method) {
                Ok(()) => self.method,
                Err(e) => {
                    let rk4 = integrator::find("rk4").expect("registered");
                    notice = Some(format!("{e}; switched to rk4"));
                    rk4
                }
            },
        };
        let dt = cmd.dt.unwrap_or(self.dt);
        if !(DT_RANGE.0..=DT_RANGE.1).contains(&dt) {
            return refuse(format!("dt = {dt}: the step must be from {} to {}", DT_RANGE.0, DT_RANGE.1));
        }
        let speed = cmd.speed.unwrap_or(self.speed);
        check_speed(speed, limits)?;
        let mode = cmd.mode.unwrap_or(self.mode);
        let methods = match &cmd.methods {
            Some(names) => names.iter().map(|n| integrator::find(n)).collect::<Result<Vec<_>, _>>()?,
            None => self.methods.clone(),
        };
        if mode == Mode::Race {
            if !(2..=limits.max_race).contains(&methods.len()) {
                return refuse(format!(
                    "a race runs 2 to {} methods, {} given ({})",
                    limits.max_race,
                    methods.len(),
                    methods.iter().map(|m| m.name).collect::<Vec<_>>().join(", ")
                ));
            }
            for m in &methods {
                built.check(m)?;
            }
        }
        let count = cmd.count.unwrap_or(self.count);
        if mode == Mode::Butterfly && !(2..=limits.max_tracks).contains(&count) {
            return refuse(format!("count = {count}: a butterfly runs 2 to {} pendulums", limits.max_tracks));
        }
        let delta = cmd.delta.unwrap_or(self.delta);
        if !(delta > 0.0 && delta <= MAX_DELTA) {
            return refuse(format!("delta = {delta}: the offset must be > 0 and at most {MAX_DELTA}"));
        }
        let poincare = cmd.poincare.unwrap_or(self.poincare && same_system);
        if poincare {
            pendula::analysis::poincare::check_system(&*built)?;
        }
        let config = Config { values, settings, method, dt, mode, methods, count, delta, speed, poincare };
        // One step of every track's method: what depends on the step as well as on the system
        // (Tao's binding constant times dt must stay at most 1) is refused now, with the
        // library's reason, rather than failing at t = 0 once running.
        for (_, m, y0) in config.tracks().iter().take(if mode == Mode::Butterfly { 1 } else { usize::MAX }) {
            let one = pendula::RunSpec { t0: 0.0, h: dt, end: pendula::End::Steps(1) };
            built.solve(m, y0, &one, &mut pendula::observe::Ignore)?;
        }
        Ok((config, notice))
    }

    /// This configuration with its start positions set to `positions` and every velocity 0.
    pub fn with_positions(&self, positions: &[f64]) -> Result<Config, Refusal> {
        let info = self.info();
        let k = info.state.len() / 2;
        if positions.len() != k {
            return refuse(format!(
                "{} positions given, {} has {k} ({})",
                positions.len(),
                info.name,
                info.state[..k].iter().map(|q| q.name).collect::<Vec<_>>().join(", ")
            ));
        }
        let mut settings = self.settings.clone();
        for (q, &v) in info.state.iter().zip(positions.iter().chain(std::iter::repeat(&0.0))) {
            if !(v.is_finite() && v.abs() <= MAX_STATE) {
                return refuse(format!(
                    "{} = {v}: start values must be finite and within ±{MAX_STATE}",
                    q.name
                ));
            }
            settings.push((q.name.to_owned(), v));
        }
        let settings = dedup(settings);
        let values = family_of(info).values(&settings)?;
        Ok(Config { values, settings, ..self.clone() })
    }

    /// The tracks this configuration runs: (label, method, start state).
    pub fn tracks(&self) -> Vec<(String, &'static Method, Vec<f64>)> {
        let y0 = self.values.initial_state().to_vec();
        match self.mode {
            Mode::Single => vec![(self.method.name.to_owned(), self.method, y0)],
            Mode::Race => self.methods.iter().map(|m| (m.name.to_owned(), *m, y0.clone())).collect(),
            Mode::Butterfly => (0..self.count)
                .map(|k| {
                    let mut y = y0.clone();
                    y[0] += k as f64 * self.delta;
                    (format!("{} + {k}δ", self.info().state[0].name), self.method, y)
                })
                .collect(),
        }
    }

    /// The `config` message.
    pub fn message(&self, paused: bool, notice: Option<&str>) -> Value {
        let info = self.info();
        let built = self.values.build();
        let y0 = self.values.initial_state();
        let params: Vec<Value> = self
            .values
            .parameters()
            .zip(info.parameters)
            .map(|((name, value), q)| {
                let (lo, hi) = bounds(q.domain);
                json!({"name": name, "unit": q.unit, "value": value, "default": q.default,
                       "domain": q.domain.describe(), "lo": lo, "hi": hi, "description": q.description})
            })
            .collect();
        let state: Vec<Value> = info
            .state
            .iter()
            .zip(y0)
            .map(|(q, v)| {
                json!({"name": q.name, "unit": q.unit, "value": v, "default": q.default, "description": q.description})
            })
            .collect();
        let poincare_available = pendula::analysis::poincare::check_system(&*built).is_ok();
        let axes: Vec<&str> =
            if info.state.len() == 4 { vec![info.state[1].name, info.state[3].name] } else { vec![] };
        let tracks: Vec<Value> =
            self.tracks().iter().map(|(label, m, _)| json!({"label": label, "method": m.name})).collect();
        json!({
            "type": "config",
            "system": family_of(info).name,
            "description": info.description,
            "dimensionless": info.dimensionless,
            "time_unit": info.time_unit(),
            "energy_unit": info.energy_unit(),
            "energy_scale": built.energy_scale(y0),
            "energy_scale_words": info.energy_scale,
            "conserves_energy": built.conserves_energy().is_ok(),
            "params": params,
            "state": state,
            "positions": info.state.len() / 2,
            "drawing": drawing(&self.values),
            "method": self.method.name,
            "dt": self.dt,
            "mode": self.mode,
            "methods": self.methods.iter().map(|m| m.name).collect::<Vec<_>>(),
            "count": self.count,
            "delta": self.delta,
            "speed": self.speed,
            "paused": paused,
            "poincare": self.poincare,
            "poincare_available": poincare_available,
            "poincare_axes": axes,
            "tracks": tracks,
            "notice": notice,
            "command": self.command(),
            "toml": self.scenario(),
            "share": self.share(),
        })
    }

    /// What a `configure` command needs to rebuild this configuration (the share URL's
    /// fragment).
    pub fn share(&self) -> Value {
        let info = self.info();
        let params: serde_json::Map<String, Value> =
            self.values.parameters().map(|(n, v)| (n.to_owned(), json!(v))).collect();
        let state: serde_json::Map<String, Value> = info
            .state
            .iter()
            .zip(self.values.initial_state())
            .map(|(q, v)| (q.name.to_owned(), json!(v)))
            .collect();
        json!({
            "system": family_of(info).name, "params": params, "state": state, "method": self.method.name,
            "dt": self.dt, "mode": self.mode, "methods": self.methods.iter().map(|m| m.name).collect::<Vec<_>>(),
            "count": self.count, "delta": self.delta, "speed": self.speed,
        })
    }

    /// Every value that differs from the catalogue's default, as `--set` would take it:
    /// the chain's links first (it picks the member the others belong to).
    fn changed(&self) -> Vec<(&'static str, f64)> {
        let info = self.info();
        let all = self
            .values
            .parameters()
            .chain(info.state.iter().map(|q| q.name).zip(self.values.initial_state().iter().copied()));
        let mut out: Vec<(&'static str, f64)> = all
            .filter(|(n, v)| info.quantity(n).map(|q: &Quantity| q.default != *v).unwrap_or(true))
            .collect();
        out.sort_by_key(|(n, _)| *n != "links");
        out
    }

    /// The first track's method: what the page's exports (its time series) hold.
    fn first_method(&self) -> &'static Method {
        self.tracks()[0].1
    }

    /// The equivalent `pendula simulate` command of the first track (in a race, the first
    /// method's run; in a butterfly, the unshifted start), the run the page's time-series
    /// exports hold.
    pub fn command(&self) -> String {
        let mut cmd = format!(
            "pendula simulate {} --method {} --dt {} --t-end 10",
            family_of(self.info()).name,
            self.first_method().name,
            self.dt
        );
        for (n, v) in self.changed() {
            cmd.push_str(&format!(" --set {n}={v}"));
        }
        cmd
    }

    /// The equivalent scenario file (`pendula simulate --scenario FILE`), of the first track.
    pub fn scenario(&self) -> String {
        let set = self
            .changed()
            .into_iter()
            .map(|(n, v)| {
                (
                    n.to_owned(),
                    if n == "links" { toml::Value::Integer(v as i64) } else { toml::Value::Float(v) },
                )
            })
            .collect();
        pendula_io::scenario::Scenario {
            system: Some(family_of(self.info()).name.to_owned()),
            method: Some(self.first_method().name.to_owned()),
            dt: Some(self.dt),
            t_end: Some(10.0),
            set,
            ..Default::default()
        }
        .to_toml()
    }
}

/// Checks a speed against the limits.
pub fn check_speed(speed: f64, limits: &Limits) -> Result<(), Refusal> {
    let hi = SPEED_RANGE.1.min(limits.max_speed);
    if !(SPEED_RANGE.0..=hi).contains(&speed) {
        return refuse(format!(
            "speed = {speed}: from {} to {hi} simulated seconds per second",
            SPEED_RANGE.0
        ));
    }
    Ok(())
}

/// The catalogue entry a system's info belongs to (the chain's members share the family's).
fn family_of(info: &'static SystemInfo) -> &'static SystemInfo {
    model::find(info.name).expect("a built system is catalogued")
}

/// The last value given for each name, in the order names first appeared.
fn dedup(settings: Vec<(String, f64)>) -> Vec<(String, f64)> {
    let mut out: Vec<(String, f64)> = Vec::new();
    for (n, v) in settings {
        match out.iter_mut().find(|(m, _)| *m == n) {
            Some(slot) => slot.1 = v,
            None => out.push((n, v)),
        }
    }
    out
}

/// A domain's bounds for the page's sliders (None: unbounded).
fn bounds(domain: Domain) -> (Option<f64>, Option<f64>) {
    match domain {
        Domain::Positive | Domain::NonNegative => (Some(0.0), None),
        Domain::Flag => (Some(0.0), Some(1.0)),
        Domain::Links => (Some(1.0), Some(pendula::system::chain::MAX_LINKS as f64)),
        _ => (None, None),
    }
}

/// How the page draws the system, from the catalogue's naming: each angle among the positions
/// is a rod hanging from the end of the one before, of the length and bob mass named by its
/// suffix (theta2 → l2, m2; theta → l, m; a dimensionless system's rod has length 1); a
/// position in metres is a block on a spring.
fn drawing(values: &Values) -> Value {
    let info = values.info();
    let positions = &info.state[..info.state.len() / 2];
    let param = |name: String, fallback: f64| {
        if info.parameters.iter().any(|q| q.name == name) { values.get(&name) } else { fallback }
    };
    if let Some((i, _)) = positions.iter().enumerate().find(|(_, q)| q.unit == "m") {
        return json!({"kind": "spring", "x": i, "mass": param("m".into(), 1.0)});
    }
    let rods: Vec<Value> = positions
        .iter()
        .enumerate()
        .filter(|(_, q)| q.is_angle() || info.dimensionless)
        .map(|(i, q)| {
            let suffix = q.name.trim_start_matches(|c: char| c.is_alphabetic());
            json!({"angle": i, "length": param(format!("l{suffix}"), 1.0), "mass": param(format!("m{suffix}"), 1.0)})
        })
        .collect();
    json!({"kind": "rods", "rods": rods})
}

#[cfg(test)]
mod tests {
    use super::*;

    fn configure(json: &str) -> Configure {
        serde_json::from_str(json).unwrap()
    }

    #[test]
    fn the_explicit_splitting_is_refused_on_the_double_pendulum_with_the_librarys_reason() {
        let c = Config::initial();
        let err = c.apply(&configure(r#"{"method":"yoshida-4"}"#), &Limits::default()).unwrap_err();
        assert!(err.0.contains("yoshida-4"), "{}", err.0);
        assert!(err.0.contains("separable"), "{}", err.0);
        let (ok, _) = c.apply(&configure(r#"{"method":"verlet"}"#), &Limits::default()).unwrap();
        assert_eq!(ok.method.name, "verlet");
    }

    #[test]
    fn a_misspelt_system_or_parameter_gets_a_suggestion() {
        let c = Config::initial();
        let err = c.apply(&configure(r#"{"system":"dubble"}"#), &Limits::default()).unwrap_err();
        assert!(err.0.contains("double"), "{}", err.0);
        let err = c.apply(&configure(r#"{"params":{"l3":1}}"#), &Limits::default()).unwrap_err();
        assert!(err.0.contains("l1") || err.0.contains("l2"), "{}", err.0);
        let err = c.apply(&configure(r#"{"params":{"m1":-1}}"#), &Limits::default()).unwrap_err();
        assert!(err.0.contains("m1") && err.0.contains("> 0"), "{}", err.0);
    }

    #[test]
    fn the_chain_draws_its_links_and_the_oscillator_a_spring() {
        let c = Config::initial();
        let (chain, _) =
            c.apply(&configure(r#"{"system":"chain","params":{"links":4}}"#), &Limits::default()).unwrap();
        let m = chain.message(false, None);
        assert_eq!(m["drawing"]["rods"].as_array().unwrap().len(), 4);
        assert_eq!(m["positions"], 4);
        let (osc, _) = c.apply(&configure(r#"{"system":"oscillator"}"#), &Limits::default()).unwrap();
        assert_eq!(osc.message(false, None)["drawing"]["kind"], "spring");
    }

    #[test]
    fn the_command_and_scenario_name_what_differs_from_the_defaults() {
        let c = Config::initial();
        let (c, _) = c
            .apply(&configure(r#"{"state":{"theta1":1.5},"method":"verlet","dt":0.02}"#), &Limits::default())
            .unwrap();
        assert_eq!(
            c.command(),
            "pendula simulate double --method verlet --dt 0.02 --t-end 10 --set theta1=1.5"
        );
        let toml = c.scenario();
        assert!(toml.contains("system = \"double\"") && toml.contains("theta1 = 1.5"), "{toml}");
    }

    #[test]
    fn a_step_too_large_for_taos_binding_is_refused_before_it_runs() {
        // At the first run's 1 ms tao-4 runs; at 10 ms its binding is too weak.
        let c = Config::initial();
        assert!(c.apply(&configure(r#"{"method":"tao-4"}"#), &Limits::default()).is_ok());
        let (c, _) = c.apply(&configure(r#"{"dt":0.01}"#), &Limits::default()).unwrap();
        let err = c.apply(&configure(r#"{"method":"tao-4"}"#), &Limits::default()).unwrap_err();
        assert!(err.0.contains("w h"), "{}", err.0);
        let err = c
            .apply(&configure(r#"{"mode":"race","methods":["rk4","tao-4"]}"#), &Limits::default())
            .unwrap_err();
        assert!(err.0.contains("w h"), "{}", err.0);
        assert!(c.apply(&configure(r#"{"method":"tao-4","dt":0.004}"#), &Limits::default()).is_ok());
    }

    #[test]
    fn a_races_exports_are_its_first_methods_run() {
        let c = Config::initial();
        let race = r#"{"mode":"race","methods":["euler","rk4"],"method":"verlet"}"#;
        let (c, _) = c.apply(&configure(race), &Limits::default()).unwrap();
        assert!(c.command().contains("--method euler"), "{}", c.command());
        assert!(c.scenario().contains("method = \"euler\""), "{}", c.scenario());
    }

    #[test]
    fn the_poincare_section_is_refused_with_the_librarys_reason() {
        let c = Config::initial();
        let limits = Limits::default();
        let (on, _) = c.apply(&configure(r#"{"poincare":true}"#), &limits).unwrap();
        assert!(on.poincare);
        assert_eq!(on.message(false, None)["poincare_available"], true);
        for (json, system, settings) in [
            (r#"{"system":"pendulum","poincare":true}"#, "pendulum", vec![]),
            (r#"{"params":{"damping":0.1},"poincare":true}"#, "double", vec![("damping".to_owned(), 0.1)]),
        ] {
            let err = c.apply(&configure(json), &limits).unwrap_err();
            let model = model::find(system).unwrap().values(&settings).unwrap().build();
            let library = pendula::analysis::poincare::check_system(&*model).unwrap_err();
            assert_eq!(err.0, library.to_string(), "{json}");
            assert!(err.0.contains("two degrees of freedom"), "{}", err.0);
            let (off, _) = c.apply(&configure(&json.replace("true", "false")), &limits).unwrap();
            assert_eq!(off.message(false, None)["poincare_available"], false, "{json}");
        }
    }

    #[test]
    fn set_state_zeroes_the_velocities() {
        let c = Config::initial();
        let (c, _) = c.apply(&configure(r#"{"state":{"omega1":2}}"#), &Limits::default()).unwrap();
        let d = c.with_positions(&[0.5, -0.25]).unwrap();
        assert_eq!(d.values.initial_state(), &[0.5, -0.25, 0.0, 0.0]);
        assert!(c.with_positions(&[0.5]).is_err());
    }
}
