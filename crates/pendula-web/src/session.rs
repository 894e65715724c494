//! One page's session: its pendulums run on a thread of their own, paced to the wall clock,
//! and publish their newest state to an [`Outbox`] that the WebSocket's writer empties as fast
//! as the page takes it (latest wins: a slow page skips frames and costs the server nothing).

use std::collections::VecDeque;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

use pendula::analysis::divergence::{Divergence, GrowthFit, growth_rate_between, state_distance};
use pendula::checkpoint::{Leg, Pause, RunState, Snapshot, Words};
use pendula::events::{EventLocator, EventSpec};
use pendula::integrator::Method;
use pendula::model::DynModel;
use pendula::observe::{Flow, Observer, Sample};
use pendula::{End, RunSpec, Stepping};
use serde::Deserialize;
use serde_json::{Value, json};

use crate::config::{Config, Configure, Mode, Refusal, check_speed};
use crate::fractal::{self, FractalRequest};
use crate::{Limits, Shared};

/// A command from the page (see PROTOCOL.md).
#[derive(Debug, Deserialize)]
#[serde(tag = "cmd", rename_all = "snake_case", deny_unknown_fields)]
pub enum Command {
    Configure(Configure),
    SetState { positions: Vec<f64> },
    Play,
    Pause,
    Step,
    Reset,
    Speed { value: f64 },
    Fractal(FractalRequest),
    FractalCancel,
    Study(crate::study::StudyRequest),
}

/// What the session thread receives: a parsed command, or text that was not one.
pub enum Inbound {
    Command(Box<Command>),
    Malformed { message: String, command: Option<String> },
}

/// What waits to be sent: text messages in order, the newest fractal level, the newest
/// growth-rate fit and the newest simulation frame (each replaced by a newer one), and the
/// Poincaré points found since the last frame sent.
#[derive(Default)]
pub struct Outbox {
    pub texts: VecDeque<String>,
    pub fractal: Option<Vec<f64>>,
    /// The newest `growth` message (a newer fit makes an unsent one worthless).
    pub growth: Option<String>,
    pub frame: Option<Vec<f64>>,
    pub poincare: Vec<[f64; 3]>,
    /// Frames replaced before they were sent (the page was slower than the simulation).
    pub skipped: u64,
}

/// Poincaré points kept for a page that does not read them (the oldest are dropped).
const MAX_PENDING_POINTS: usize = 20_000;

/// Text messages kept for a page that does not read them (the oldest are dropped): a page
/// that sends commands and never reads the answers must not grow the server's memory.
const MAX_PENDING_TEXTS: usize = 256;

impl Shared {
    fn text(&self, message: &Value) {
        let mut outbox = self.outbox.lock().expect("outbox");
        if outbox.texts.len() >= MAX_PENDING_TEXTS {
            outbox.texts.pop_front();
        }
        outbox.texts.push_back(message.to_string());
        drop(outbox);
        self.notify.notify_one();
    }
    fn error(&self, message: &str, command: Option<&str>) {
        self.text(&json!({"type": "error", "message": message, "command": command}));
    }
}

/// The butterfly's growth-rate fit (the `growth` message, PROTOCOL.md) uses the distance of
/// pendulum 1 from pendulum 0 above `FIT_FROM_OFFSETS` times their offset δ (at most
/// `FIT_FROM_MAX`): below it the separation has not yet turned along the most unstable
/// direction and grows at other rates (early fits even came out negative).
const FIT_FROM_OFFSETS: f64 = 100.0;
/// See [`FIT_FROM_OFFSETS`].
const FIT_FROM_MAX: f64 = 1e-2;
/// ... and before the distance first exceeds this, where the separation stops growing
/// exponentially (the largest swings are a few radians).
const FIT_SATURATION: f64 = 0.1;
/// Distance samples kept for the fit; at this many every other one is dropped and the
/// sampling interval doubled, so that a separation that never saturates (a regular orbit)
/// costs bounded memory.
const MAX_GROWTH_SAMPLES: usize = 4096;

/// The time the simulation may run to: no end the page would reach (10⁶ s at the largest speed is
/// 17 minutes), yet a finite schedule.
const HORIZON: f64 = 1e6;

/// One pendulum of the session.
struct Track {
    /// Its place among the session's tracks (the Poincaré points name it).
    index: usize,
    method: &'static Method,
    y0: Vec<f64>,
    run: Option<RunState>,
    t: f64,
    y: Vec<f64>,
    steps: u64,
    e0: f64,
    scale: f64,
    flip: f64,
    locator: Option<Words>,
    over: bool,
    /// The states kept for the butterfly's divergence (pendulums 0 and 1, until the fit is
    /// final), not yet paired with the other pendulum's.
    kept: Option<Kept>,
}

/// The states of every `every`-th step (steps 0, every, 2·every, …: the samples
/// `pendula::analysis::divergence` keeps), as (step, t, state).
struct Kept {
    every: u64,
    rows: Vec<(u64, f64, Vec<f64>)>,
}

/// Keeps the newest state of a leg (and the states `kept` asks for).
struct Newest<'a> {
    t: &'a mut f64,
    y: &'a mut [f64],
    steps: &'a mut u64,
    kept: Option<&'a mut Kept>,
}

impl Observer for Newest<'_> {
    fn observe(&mut self, s: &Sample<'_>) -> Flow {
        *self.t = s.t;
        *self.steps = s.step;
        self.y.copy_from_slice(s.y);
        if let Some(kept) = &mut self.kept
            && s.step.is_multiple_of(kept.every)
        {
            kept.rows.push((s.step, s.t, s.y.to_vec()));
        }
        Flow::Continue(())
    }
}

impl Track {
    fn new(index: usize, model: &dyn DynModel, method: &'static Method, y0: Vec<f64>) -> Track {
        let e0 = model.energy(0.0, &y0);
        let scale = model.energy_scale(&y0);
        Track {
            index,
            method,
            y: y0.clone(),
            y0,
            run: None,
            t: 0.0,
            steps: 0,
            e0,
            scale,
            flip: f64::NAN,
            locator: None,
            over: false,
            kept: None,
        }
    }

    /// Runs this track on to `target` (or at most `max_steps` steps), continuing the run
    /// where the last leg paused: the same steps, in the same bits, as one uninterrupted run.
    fn advance(
        &mut self,
        model: &dyn DynModel,
        h: f64,
        target: f64,
        max_steps: u64,
        specs: &[EventSpec],
        points: &mut Vec<[f64; 3]>,
    ) -> Result<(), pendula::Error> {
        let target = target.min(self.t + max_steps as f64 * h);
        if self.over || target <= self.t {
            return Ok(());
        }
        let stepping = Stepping::Fixed(RunSpec { t0: 0.0, h, end: End::Time(HORIZON) });
        let mut locator = EventLocator::new(model, specs.to_vec());
        if let Some(words) = &self.locator {
            locator.restore_all(words, "the event locator")?;
        }
        let pause = Pause { at: target, flag: None };
        let leg = {
            let mut newest =
                Newest { t: &mut self.t, y: &mut self.y, steps: &mut self.steps, kept: self.kept.as_mut() };
            model.solve_fastest(
                self.method,
                &self.y0,
                &stepping,
                &mut (&mut newest, &mut locator),
                self.run.as_ref(),
                &pause,
            )?
        };
        match leg {
            Leg::Paused(state) => self.run = Some(state),
            Leg::Done(_) => self.over = true,
        }
        let angle = model.info().state.get(1).is_some_and(|q| q.is_angle());
        for event in locator.found.drain(..) {
            if event.name == "flip" {
                if self.flip.is_nan() {
                    self.flip = event.t;
                }
            } else if event.state.len() == 4 {
                // The section's angle in [−π, π): the section is of the torus, not of the
                // unwrapped line a rotating pendulum's angle runs along.
                let x = if angle { pendula::system::wrap_angle(event.state[1]) } else { event.state[1] };
                points.push([self.index as f64, x, event.state[3]]);
            }
        }
        self.locator = Some(locator.snapshot());
        Ok(())
    }
}

/// The butterfly's measured divergence: the distance of pendulum 1 from pendulum 0, started
/// δ apart in the first state variable (the two runs of `pendula divergence`), sampled on
/// whole steps, and the library's fit of its growth rate.
struct Growth {
    from: f64,
    /// The sampling interval, steps (doubled each time [`MAX_GROWTH_SAMPLES`] is reached).
    every: u64,
    d: Divergence,
    fit: Option<GrowthFit>,
    /// The distance has exceeded [`FIT_SATURATION`]: later samples cannot change the fit.
    done: bool,
    /// The fit changed since the last `growth` message.
    unsent: bool,
}

impl Growth {
    fn new(delta: f64) -> Growth {
        Growth {
            from: (FIT_FROM_OFFSETS * delta).min(FIT_FROM_MAX),
            every: 1,
            d: Divergence { t: Vec::new(), distance: Vec::new() },
            fit: None,
            done: false,
            unsent: false,
        }
    }

    /// Pairs the states pendulums 0 and 1 kept on the same steps into distances, and fits
    /// again.
    fn take(&mut self, a: &mut Kept, b: &mut Kept) {
        let (mut i, mut j, before) = (0, 0, self.d.t.len());
        while i < a.rows.len() && j < b.rows.len() {
            let ((sa, t, ya), (sb, _, yb)) = (&a.rows[i], &b.rows[j]);
            match sa.cmp(sb) {
                std::cmp::Ordering::Less => i += 1,
                std::cmp::Ordering::Greater => j += 1,
                std::cmp::Ordering::Equal => {
                    self.d.t.push(*t);
                    self.d.distance.push(state_distance(ya, yb));
                    i += 1;
                    j += 1;
                }
            }
        }
        a.rows.drain(..i);
        b.rows.drain(..j);
        if self.d.t.len() == before {
            return;
        }
        self.fit = growth_rate_between(&self.d, self.from, FIT_SATURATION);
        self.done = self.d.distance[before..].iter().any(|&x| x > FIT_SATURATION);
        self.unsent = self.fit.is_some() || self.done;
        if !self.done && self.d.t.len() >= MAX_GROWTH_SAMPLES {
            let keep = |v: &mut Vec<f64>| {
                let mut k = 0;
                v.retain(|_| {
                    k += 1;
                    k % 2 == 1
                });
            };
            keep(&mut self.d.t);
            keep(&mut self.d.distance);
            self.every *= 2;
            for kept in [a, b] {
                kept.every = self.every;
                kept.rows.retain(|r| r.0.is_multiple_of(self.every));
            }
        }
    }

    /// The `growth` message (PROTOCOL.md), at the run's time `t`.
    fn message(&self, t: f64) -> Value {
        json!({
            "type": "growth",
            "t": t,
            "rate": self.fit.map(|f| f.rate),
            "t_start": self.fit.map(|f| f.t_start),
            "t_end": self.fit.map(|f| f.t_end),
            "intercept": self.fit.map(|f| f.intercept),
            "final": self.done,
            "fit_from": self.from,
            "saturation": FIT_SATURATION,
            "every": self.every,
            "samples": self.d.t.len(),
        })
    }
}

/// The running simulation of a configuration.
struct Sim {
    config: Config,
    model: Box<dyn DynModel>,
    tracks: Vec<Track>,
    specs: Vec<EventSpec>,
    paused: bool,
    failed: bool,
    /// The simulated time the wall clock has asked for so far. Kept apart from the tracks'
    /// time, which ends on whole steps past it: rounding each frame up to a whole step
    /// would make the simulation run fast (at 60 frames a second and dt = 0.01 s, speed 1
    /// ran at 1.19).
    target: f64,
    /// The butterfly's growth rate (None in the other modes).
    growth: Option<Growth>,
}

impl Sim {
    fn new(config: Config, paused: bool) -> Sim {
        let model = config.values.build();
        let mut tracks: Vec<Track> = config
            .tracks()
            .into_iter()
            .enumerate()
            .map(|(i, (_, m, y0))| Track::new(i, &*model, m, y0))
            .collect();
        let growth = (config.mode == Mode::Butterfly).then(|| Growth::new(config.delta));
        if growth.is_some() {
            for track in &mut tracks[..2] {
                track.kept = Some(Kept { every: 1, rows: Vec::new() });
            }
        }
        let mut specs = Vec::new();
        if config.info().state.iter().any(|q| q.is_angle()) {
            specs.push(EventSpec::parse("flip", &*model, false).expect("a system with angles has flips"));
        }
        if config.poincare {
            // The section θ₁ = 0 crossed upwards, plotted in (θ₂, ω₂): `pendula poincare`'s.
            let name = format!("section:{}=0+", config.info().state[0].name);
            specs.push(EventSpec::parse(&name, &*model, false).expect("a 2-DOF system's first position"));
        }
        Sim { config, model, tracks, specs, paused, failed: false, target: 0.0, growth }
    }

    fn restart(&mut self) {
        let paused = self.paused;
        *self = Sim::new(self.config.clone(), paused);
    }

    fn t(&self) -> f64 {
        self.tracks[0].t
    }

    /// Advances every track to `target`, at most `budget` steps in all.
    fn advance(
        &mut self,
        target: f64,
        budget: u64,
        points: &mut Vec<[f64; 3]>,
    ) -> Result<(), pendula::Error> {
        let per_track = (budget / self.tracks.len() as u64).max(1);
        let result = self.tracks.iter_mut().try_for_each(|track| {
            track.advance(&*self.model, self.config.dt, target, per_track, &self.specs, points)
        });
        // The steps both pendulums took, even those before a failure.
        if let Some(growth) = &mut self.growth
            && let [a, b, ..] = &mut self.tracks[..]
            && let (Some(ka), Some(kb)) = (&mut a.kept, &mut b.kept)
        {
            growth.take(ka, kb);
            if growth.done {
                a.kept = None;
                b.kept = None;
            }
        }
        result
    }

    /// The `growth` message when the fit changed since the last one.
    fn growth_message(&mut self) -> Option<Value> {
        let t = self.t();
        let growth = self.growth.as_mut().filter(|g| g.unsent)?;
        growth.unsent = false;
        Some(growth.message(t))
    }

    /// The binary frame (see PROTOCOL.md), without its Poincaré points (added when sent).
    fn frame(&self, seq: u64) -> Vec<f64> {
        let d = self.tracks[0].y.len();
        let k = d / 2;
        let mut out = Vec::with_capacity(7 + self.tracks.len() * (d + 4));
        out.extend([1.0, seq as f64, self.t(), self.tracks.len() as f64, d as f64, f64::from(self.paused)]);
        out.push(self.tracks[0].steps as f64);
        let mut rest = vec![0.0; d];
        for track in &self.tracks {
            let energy = self.model.energy(track.t, &track.y);
            rest[..k].copy_from_slice(&track.y[..k]);
            let potential = self.model.energy(track.t, &rest);
            out.extend_from_slice(&track.y);
            out.extend([energy - potential, potential, (energy - track.e0).abs() / track.scale, track.flip]);
        }
        out
    }
}

/// Runs one session until the page goes away (the sender of `inbox` is dropped).
pub fn run(inbox: Receiver<Inbound>, shared: Arc<Shared>, limits: Limits) {
    let mut sim = Sim::new(Config::initial(), false);
    let hello = crate::hello(&limits);
    shared.text(&hello);
    shared.text(&sim.config.message(sim.paused, None));
    let interval = Duration::from_secs_f64(1.0 / limits.max_fps);
    let mut clock = Instant::now();
    let mut seq = 0u64;
    let mut fractal_cancel: Option<Arc<AtomicBool>> = None;
    let mut job = 0u64;
    // One fractal thread per session at a time: a newer request cancels the running one and
    // waits here until that thread has ended (however many requests come meanwhile, only
    // the newest is kept).
    let mut fractal_thread: Option<std::thread::JoinHandle<()>> = None;
    let mut fractal_next: Option<(fractal::Job, u64, Arc<AtomicBool>)> = None;
    let mut next = Instant::now();
    loop {
        // Commands first: wait for one until the next frame is due (or, paused, a while; a
        // fractal waiting for the previous one's thread to end is looked at often).
        let wait = if fractal_next.is_some() {
            Duration::from_millis(10)
        } else if sim.paused || sim.failed {
            Duration::from_millis(250)
        } else {
            next.saturating_duration_since(Instant::now())
        };
        let mut first = match inbox.recv_timeout(wait) {
            Ok(m) => Some(m),
            Err(RecvTimeoutError::Timeout) => None,
            Err(RecvTimeoutError::Disconnected) => break,
        };
        let mut changed = false;
        while let Some(message) = first.take().or_else(|| inbox.try_recv().ok()) {
            let cmd = match message {
                Inbound::Malformed { message, command } => {
                    shared.error(&message, command.as_deref());
                    continue;
                }
                Inbound::Command(c) => *c,
            };
            let name = command_name(&cmd);
            let publish = |sim: &mut Sim, config: Config, notice: Option<String>| {
                sim.config = config;
                sim.restart();
                forget_growth(&shared);
                shared.text(&sim.config.message(sim.paused, notice.as_deref()));
            };
            let result: Result<(), Refusal> = match cmd {
                Command::Configure(c) => sim.config.apply(&c, &limits).map(|(config, notice)| {
                    publish(&mut sim, config, notice);
                    changed = true;
                }),
                Command::SetState { positions } => sim.config.with_positions(&positions).map(|config| {
                    publish(&mut sim, config, None);
                    changed = true;
                }),
                Command::Play => {
                    sim.paused = false;
                    Ok(())
                }
                Command::Pause => {
                    sim.paused = true;
                    changed = true;
                    Ok(())
                }
                Command::Reset => {
                    sim.restart();
                    forget_growth(&shared);
                    changed = true;
                    Ok(())
                }
                Command::Step => {
                    if sim.paused && !sim.failed {
                        // Half a step ahead: the run pauses after exactly one step.
                        let target = sim.t() + 0.5 * sim.config.dt;
                        let mut points = Vec::new();
                        if let Err(e) = sim.advance(target, u64::MAX, &mut points) {
                            fail(&shared, &mut sim, &e);
                        }
                        sim.target = sim.t();
                        queue_points(&shared, points);
                        changed = true;
                    }
                    Ok(())
                }
                Command::Speed { value } => check_speed(value, &limits).map(|()| sim.config.speed = value),
                Command::Fractal(request) => match request.validate(&limits, &sim.config) {
                    Ok(spec) => {
                        if let Some(flag) = fractal_cancel.take() {
                            flag.store(true, Ordering::Relaxed);
                        }
                        job += 1;
                        let flag = Arc::new(AtomicBool::new(false));
                        fractal_cancel = Some(flag.clone());
                        fractal_next = Some((spec, job, flag));
                        Ok(())
                    }
                    Err(r) => Err(r),
                },
                // Bounded by the limit on its steps, so it holds the live run back briefly.
                Command::Study(request) => {
                    crate::study::run(request, &limits).map(|message| shared.text(&message))
                }
                Command::FractalCancel => {
                    if let Some(flag) = fractal_cancel.take() {
                        flag.store(true, Ordering::Relaxed);
                    }
                    fractal_next = None;
                    Ok(())
                }
            };
            if let Err(Refusal(message)) = result {
                shared.error(&message, Some(name));
            }
        }
        if fractal_next.is_some() && fractal_thread.as_ref().is_none_or(std::thread::JoinHandle::is_finished)
        {
            let (spec, id, flag) = fractal_next.take().expect("checked");
            fractal_thread = Some(fractal::start(spec, id, flag, shared.clone()));
        }
        let now = Instant::now();
        if !sim.paused && !sim.failed && now >= next {
            // The simulated time the wall clock asks for; a run that cannot keep up falls
            // behind (its work per frame is bounded) rather than stalling the session.
            let elapsed = now.duration_since(clock).as_secs_f64().min(0.25);
            sim.target += sim.config.speed * elapsed;
            let mut points = Vec::new();
            if let Err(e) = sim.advance(sim.target, limits.max_steps_per_frame, &mut points) {
                fail(&shared, &mut sim, &e);
            }
            // Behind by more than a quarter of a second of wall time (the step budget ran
            // out): the simulation falls behind rather than owing the clock for ever.
            sim.target = sim.target.min(sim.t() + 0.25 * sim.config.speed);
            queue_points(&shared, points);
            changed = true;
            next = now + interval;
            clock = now;
        } else if sim.paused || sim.failed {
            // Time spent paused is not simulated when the clock starts again.
            clock = now;
        }
        if changed {
            seq += 1;
            let frame = sim.frame(seq);
            let growth = sim.growth_message();
            let mut outbox = shared.outbox.lock().expect("outbox");
            if let Some(g) = growth {
                outbox.growth = Some(g.to_string());
            }
            if outbox.frame.replace(frame).is_some() {
                outbox.skipped += 1;
            }
            drop(outbox);
            shared.notify.notify_one();
        }
    }
    if let Some(flag) = fractal_cancel {
        flag.store(true, Ordering::Relaxed);
    }
}

/// A restarted run's fit starts afresh: an unsent one of the run before must not follow the
/// new run's `config`.
fn forget_growth(shared: &Shared) {
    shared.outbox.lock().expect("outbox").growth = None;
}

fn queue_points(shared: &Shared, points: Vec<[f64; 3]>) {
    if points.is_empty() {
        return;
    }
    let mut outbox = shared.outbox.lock().expect("outbox");
    outbox.poincare.extend(points);
    let excess = outbox.poincare.len().saturating_sub(MAX_PENDING_POINTS);
    outbox.poincare.drain(..excess);
}

/// A failed run stops the clock and says when it failed.
fn fail(shared: &Shared, sim: &mut Sim, e: &pendula::Error) {
    sim.failed = true;
    sim.paused = true;
    let t = sim.t();
    shared
        .text(&json!({"type": "run_failed", "message": format!("the run failed near t = {t}: {e}"), "t": t}));
}

fn command_name(cmd: &Command) -> &'static str {
    match cmd {
        Command::Configure(_) => "configure",
        Command::SetState { .. } => "set_state",
        Command::Play => "play",
        Command::Pause => "pause",
        Command::Step => "step",
        Command::Reset => "reset",
        Command::Speed { .. } => "speed",
        Command::Fractal(_) => "fractal",
        Command::FractalCancel => "fractal_cancel",
        Command::Study(_) => "study",
    }
}
