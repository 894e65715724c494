//! The fractal explorer's computation: the double pendulum's flip-time map on the ensemble
//! engine (`pendula::analysis::fractal`, the code behind `pendula fractal`), refined level by
//! level — 32², 64², … up to the size asked — so that a coarse map is on the page at once;
//! the last level also carries the convergence flags (a second run at dt/2).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use pendula::analysis::fractal::{FractalSpec, GridAxis, converged, flip_times_at};
use pendula::integrator;
use serde::Deserialize;
use serde_json::json;

use crate::config::Config;
use crate::{Limits, Shared};

/// The `fractal` command.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FractalRequest {
    size: Option<usize>,
    t_max: Option<f64>,
    theta1: Option<[f64; 2]>,
    theta2: Option<[f64; 2]>,
    method: Option<String>,
    dt: Option<f64>,
}

/// The smallest map sent first.
const FIRST_LEVEL: usize = 32;
/// Flip times agree when within this, s (`pendula fractal`'s default tolerance).
const TOLERANCE: f64 = 0.01;

/// A validated fractal request: the spec of its finest level.
pub struct Job {
    spec: FractalSpec,
}

impl FractalRequest {
    /// Checks the request against the limits; the pendulum is the session's double pendulum
    /// (its masses, lengths and g) or the catalogue's default one.
    pub fn validate(&self, limits: &Limits, session: &Config) -> Result<Job, crate::config::Refusal> {
        let refuse = |m: String| Err(crate::config::Refusal(m));
        let size = self.size.unwrap_or(512);
        if !(16..=limits.max_fractal_size).contains(&size) {
            return refuse(format!(
                "size = {size}: the map is 16 to {} pixels per side",
                limits.max_fractal_size
            ));
        }
        let t_max = self.t_max.unwrap_or(100.0);
        if !(t_max > 0.0 && t_max <= limits.max_t_max) {
            return refuse(format!(
                "t_max = {t_max}: the horizon must be > 0 and at most {} s",
                limits.max_t_max
            ));
        }
        let dt = self.dt.unwrap_or(0.01);
        if !(1e-4..=0.1).contains(&dt) {
            return refuse(format!("dt = {dt}: the fractal's step must be from 0.0001 to 0.1 s"));
        }
        if t_max / dt > 1e7 {
            return refuse(format!("t_max / dt = {:.0} steps per pixel: at most 10^7", t_max / dt));
        }
        let method = integrator::find(self.method.as_deref().unwrap_or("rk4"))?;
        let axis = |name: &str, range: Option<[f64; 2]>| -> Result<GridAxis, crate::config::Refusal> {
            let [lo, hi] = range.unwrap_or([-std::f64::consts::PI, std::f64::consts::PI]);
            if !(lo.is_finite()
                && hi.is_finite()
                && lo < hi
                && hi - lo >= 1e-9
                && lo.abs() <= 100.0
                && hi.abs() <= 100.0)
            {
                return Err(crate::config::Refusal(format!(
                    "{name} = [{lo}, {hi}]: the range must be finite, lo < hi (by at least 1e-9 rad), within ±100 rad"
                )));
            }
            Ok(GridAxis { lo, hi, n: size })
        };
        let (theta1, theta2) = (axis("theta1", self.theta1)?, axis("theta2", self.theta2)?);
        // The session's masses, lengths and g when it runs the double pendulum; the free
        // pendulum's equations either way (the kernels' own).
        let double = pendula::model::find("double")?;
        let values =
            if session.info().name == "double" { session.values.clone() } else { double.values(&[])? };
        let mut settings: Vec<(String, f64)> =
            ["m1", "m2", "l1", "l2", "g"].iter().map(|n| (n.to_string(), values.get(n))).collect();
        settings.push(("damping".into(), 0.0));
        settings.push(("drive_amplitude".into(), 0.0));
        // The library's checks (the method among those the engine runs on it, Tao's step).
        Ok(Job {
            spec: FractalSpec::new(&double.values(&settings)?, theta1, theta2, t_max, dt, method, TOLERANCE)?,
        })
    }
}

/// Only one map is computed at a time across all sessions: each uses every core.
static ENGINE: Mutex<()> = Mutex::new(());

/// The name of every fractal thread (`/proc/self/task/*/comm`), so that tests can count them.
pub const THREAD_NAME: &str = "pendula-fractal";

/// Starts computing `job` on a thread of its own; `cancel` stops it between work items.
pub fn start(job: Job, id: u64, cancel: Arc<AtomicBool>, shared: Arc<Shared>) -> std::thread::JoinHandle<()> {
    let thread = std::thread::Builder::new().name(THREAD_NAME.into());
    // Spawning fails only when the OS is out of threads; nothing can be computed then.
    thread
        .spawn(move || {
            let _engine = ENGINE.lock().unwrap_or_else(|e| e.into_inner());
            let begin = Instant::now();
            let finest = job.spec.theta1.n;
            let mut n = FIRST_LEVEL.min(finest);
            loop {
                if cancel.load(Ordering::Relaxed) {
                    return;
                }
                let last = n == finest;
                let spec = FractalSpec {
                    theta1: GridAxis { n, ..job.spec.theta1 },
                    theta2: GridAxis { n, ..job.spec.theta2 },
                    ..job.spec
                };
                let pixels = 0..n * n;
                let times = match flip_times_at(&spec, spec.h, pixels.clone(), &|_| (), Some(&cancel)) {
                    Ok(t) => t,
                    Err(pendula::Error::Interrupted) => return,
                    Err(e) => return failed(&shared, &e, &cancel),
                };
                let flags = if last {
                    match flip_times_at(&spec, spec.h / 2.0, pixels, &|_| (), Some(&cancel)) {
                        Ok(half) => Some(
                            times
                                .iter()
                                .zip(&half)
                                .map(|(a, b)| f64::from(u8::from(converged(*a, *b, TOLERANCE))))
                                .collect::<Vec<_>>(),
                        ),
                        Err(pendula::Error::Interrupted) => return,
                        Err(e) => return failed(&shared, &e, &cancel),
                    }
                } else {
                    None
                };
                let seconds = begin.elapsed().as_secs_f64();
                let mut frame = Vec::with_capacity(12 + 2 * n * n);
                frame.extend([2.0, id as f64, n as f64, n as f64, spec.t_max]);
                frame.extend([spec.theta1.lo, spec.theta1.hi, spec.theta2.lo, spec.theta2.hi]);
                frame.extend([f64::from(u8::from(flags.is_some())), f64::from(u8::from(last)), seconds]);
                frame.extend_from_slice(&times);
                if let Some(f) = &flags {
                    frame.extend_from_slice(f);
                }
                if cancel.load(Ordering::Relaxed) {
                    return;
                }
                {
                    let mut outbox = shared.outbox.lock().expect("outbox");
                    outbox.fractal = Some(frame);
                    if last {
                        let done = json!({"type": "fractal_done", "job": id, "size": n, "seconds": seconds});
                        outbox.texts.push_back(done.to_string());
                    }
                }
                shared.notify.notify_one();
                if last {
                    return;
                }
                n = (2 * n).min(finest);
            }
        })
        .expect("the OS gives a thread for the fractal")
}

fn failed(shared: &Shared, e: &pendula::Error, cancel: &AtomicBool) {
    if !cancel.load(Ordering::Relaxed) {
        let message =
            json!({"type": "error", "message": format!("the fractal failed: {e}"), "command": "fractal"});
        shared.outbox.lock().expect("outbox").texts.push_back(message.to_string());
        shared.notify.notify_one();
    }
}
