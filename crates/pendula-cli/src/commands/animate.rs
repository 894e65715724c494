//! `pendula animate`: rods, bobs, a fading trail, the time and an energy gauge, as GIF or
//! MP4; `--compare DELTA` adds a second pendulum started DELTA radians away (paper §1:
//! sensitivity to initial conditions).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::{Context, Result, bail};
use clap::Args;
use pendula::analysis::EnergySeries;
use pendula::observe::{Every, Recorder};
use pendula::{End, RunSpec};
use pendula_viz::{Animation, Snapshot};

use crate::args::{Defaults, EndArg, LargeArg, MethodArgs, SetArgs, SystemArg};
use crate::output::{AtomicFile, CreatedDirs, WatchedChild};
use crate::parse::parse_value;
use crate::study;

#[derive(Debug, Clone, Args)]
pub struct AnimateArgs {
    #[command(flatten)]
    pub system: SystemArg,
    #[command(flatten)]
    pub stepping: MethodArgs,
    #[command(flatten)]
    pub end: EndArg,
    #[command(flatten)]
    pub set: SetArgs,
    /// Output: FILE.gif, or FILE.mp4 (needs ffmpeg on the PATH) [default: pendula-out/animate/animation.gif].
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Add a second pendulum whose first angle starts DELTA radians (or `1e-3deg`) away.
    #[arg(long, value_name = "DELTA", allow_hyphen_values = true)]
    pub compare: Option<String>,
    /// Frames per second of simulated time. A GIF plays 1 to 50 exactly (its
    /// delays are whole centiseconds, alternated, e.g. 3, 3, 4 cs for 30 fps); MP4 up to 240.
    #[arg(long, value_name = "N")]
    pub fps: Option<String>,
    /// Frame size in pixels, WIDTHxHEIGHT.
    #[arg(long, value_name = "WxH")]
    pub size: Option<String>,
    #[command(flatten)]
    pub large: LargeArg,
}

/// What animate runs without arguments.
pub const DEFAULTS: Defaults = crate::args::Defaults::of(
    &pendula::study::defaults::ANIMATE,
    &[
        ("system", "A pendulum or the double pendulum."),
        ("t_end", "The length of the animation in simulated seconds."),
        ("set", "`--set theta1=120deg` for the double pendulum, `--set theta=120deg` for the pendulum."),
    ],
);

pub fn run(args: &AnimateArgs) -> Result<()> {
    let system = args.system.name(&DEFAULTS);
    if !matches!(system, "pendulum" | "double") {
        bail!("invalid system `{system}` for animate: it draws pendulums; use pendulum or double");
    }
    let method = args.stepping.method(&DEFAULTS)?;
    let h = args.stepping.dt(&DEFAULTS)?;
    let t_end = args.end.t_end(&DEFAULTS)?;
    let fps = match &args.fps {
        Some(text) => {
            crate::parse::parse_count("--fps", text, 1, 240, "frames per second (1 to 50 for a GIF)")? as u32
        }
        None => DEFAULTS.of.count("fps") as u32,
    };
    let size = parse_size(args.size.as_deref().unwrap_or(DEFAULTS.of.text("size")))?;
    let out = args.out.clone().unwrap_or_else(|| PathBuf::from("pendula-out/animate/animation.gif"));
    if out == Path::new("-") {
        bail!("invalid --out -: animate writes a GIF or MP4 file, not stdout; give FILE.gif or FILE.mp4");
    }
    let mp4 = match out.extension().and_then(|e| e.to_str()) {
        Some("gif") => false,
        Some("mp4") => true,
        _ => bail!("invalid --out `{}`: use FILE.gif or FILE.mp4", out.display()),
    };
    if !mp4 && fps > 50 {
        bail!(
            "invalid --fps {fps} for a GIF: GIF delays are whole centiseconds, and browsers slow delays under 2 cs to 10 cs; use 1 to 50, or write an .mp4"
        );
    }
    if mp4 && !ffmpeg_available() {
        bail!(
            "MP4 output needs an `ffmpeg` binary on the PATH, and none was found; install ffmpeg or write a .gif"
        );
    }
    let values = study::values(system, &args.set.items)?;
    let first = values.info().state[0];
    let delta = args.compare.as_deref().map(|d| parse_value("--compare", d, Some(&first))).transpose()?;
    if let Some(d) = delta
        && !d.is_finite()
    {
        bail!("invalid --compare {d}: must be finite");
    }
    let spec = RunSpec { t0: 0.0, h, end: End::Time(t_end) };
    let schedule = crate::parse::schedule(&spec, "--dt", "--t-end")?;
    // What it costs: the runs, and the frames' bytes (GIF or MP4 keep the animation in
    // memory until it is written): the default animation's GIF takes 0.03 bytes a pixel,
    // counted here as 0.05.
    let runs = if delta.is_some() { 2.0 } else { 1.0 };
    let frames = (t_end * fps as f64).ceil() + 1.0;
    let bytes = frames * size.0 as f64 * size.1 as f64 * 0.05;
    let how = format!("{} frames of {}x{} pixels", crate::limits::round(frames), size.0, size.1);
    crate::limits::check(
        "animate",
        args.large.allow_large,
        &[
            crate::limits::Estimate::new(
                crate::limits::Cost::Steps,
                runs * schedule.steps as f64,
                format!("{runs} runs x {} steps", crate::limits::round(schedule.steps as f64)),
            ),
            crate::limits::Estimate::new(crate::limits::Cost::Output, bytes, how.clone()),
            crate::limits::Estimate::new(crate::limits::Cost::Memory, bytes, how),
        ],
    )?;
    // The default's directory is made for it, and removed again if the run fails.
    let created = match out.parent() {
        Some(dir) if !dir.as_os_str().is_empty() && args.out.is_none() => {
            Some(CreatedDirs::create(dir, "--out")?)
        }
        _ => None,
    };
    let file = AtomicFile::create(&out, "--out")?;

    // A frame too small for the text, the gauges and a pendulum is refused before the run.
    Animation {
        title: String::new(),
        lengths: vec![1.0],
        frames: vec![Snapshot {
            t: 0.0,
            angles: vec![],
            energy_error: vec![0.0; 1 + delta.is_some() as usize],
        }],
        size,
        fps,
        trail: 0,
        labels: vec![],
    }
    .layout()
    .map_err(|e| anyhow::anyhow!("invalid --size {}x{}: {e}", size.0, size.1))?;
    let frames = snapshots(&values, method, &spec, fps, delta)?;
    let lengths: Vec<f64> = match system {
        "pendulum" => vec![values.get("l")],
        _ => vec![values.get("l1"), values.get("l2")],
    };
    // Each pendulum is named by its start, and the second by what differs from the first.
    let start = format!(
        "{} = {}°",
        pendula_viz::pretty(first.name),
        pendula_viz::number(values.initial_state()[0].to_degrees())
    );
    let mut labels = vec![start.clone()];
    if let Some(d) = delta {
        let sign = if d < 0.0 { "−" } else { "+" };
        labels.push(format!("{start} {sign} {} rad", pendula_viz::number(d.abs())));
    }
    let animation = Animation {
        title: format!("{system} pendulum, {}, h = {h} s", method.name),
        lengths,
        frames,
        size,
        fps,
        trail: (fps as usize * 2).max(2),
        labels,
    };
    if mp4 {
        encode_mp4(&animation, &file)?;
    } else {
        file.write_all(&animation.gif()?)?;
    }
    file.commit()?;
    if let Some(created) = created {
        created.keep();
    }
    eprintln!("wrote {} ({} frames, {}x{})", out.display(), animation.frames.len(), size.0, size.1);
    Ok(())
}

/// One snapshot every 1/fps s of simulated time (rounded to whole steps) of the pendulum
/// from `values`, and of a second one whose first angle starts `delta` rad away.
pub fn snapshots(
    values: &pendula::system::Values,
    method: &pendula::integrator::Method,
    spec: &RunSpec,
    fps: u32,
    delta: Option<f64>,
) -> Result<Vec<Snapshot>> {
    let every = ((1.0 / (fps as f64 * spec.h)).round() as u64).max(1);
    let mut starts = vec![values.initial_state().to_vec()];
    if let Some(d) = delta {
        let mut y = values.initial_state().to_vec();
        y[0] += d;
        starts.push(y);
    }
    let model = values.build();
    let n = values.info().state.len() / 2;
    let (mut tracks, mut errors) = (Vec::new(), Vec::new());
    for y0 in &starts {
        let mut rec = Every { n: every, inner: Recorder::default() };
        // Relative to the system's energy scale; sampled at the same steps as the frames.
        let mut energy = EnergySeries::new(&*model, y0, every);
        model.solve(method, y0, spec, &mut (&mut rec, &mut energy))?;
        tracks.push(rec.inner.rows);
        errors.push(energy.error);
    }
    let row = 2 * n + 1;
    Ok((0..tracks[0].len() / row)
        .map(|k| {
            let rows: Vec<&[f64]> = tracks.iter().map(|t| &t[k * row..(k + 1) * row]).collect();
            Snapshot {
                t: rows[0][0],
                angles: rows.iter().map(|r| r[1..=n].to_vec()).collect(),
                energy_error: errors.iter().map(|e| e[k].abs()).collect(),
            }
        })
        .collect())
}

fn parse_size(text: &str) -> Result<(u32, u32)> {
    let bad =
        || anyhow::anyhow!("invalid --size `{text}`: expected WIDTHxHEIGHT, each 64 to 4096, e.g. 480x480");
    let (w, h) = text.split_once('x').ok_or_else(bad)?;
    let (w, h): (u32, u32) = (w.trim().parse().map_err(|_| bad())?, h.trim().parse().map_err(|_| bad())?);
    if !(64..=4096).contains(&w) || !(64..=4096).contains(&h) {
        return Err(bad());
    }
    Ok((w, h))
}

fn ffmpeg_available() -> bool {
    Command::new("ffmpeg")
        .arg("-version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Pipes raw RGB frames into ffmpeg, which writes H.264 into the temporary file.
fn encode_mp4(animation: &Animation, file: &AtomicFile) -> Result<()> {
    let (w, h) = animation.size;
    let target = file.temp_path();
    let mut command = Command::new("ffmpeg");
    command
        .args(["-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24"])
        .args(["-s", &format!("{w}x{h}"), "-r", &animation.fps.to_string(), "-i", "-"])
        .args(["-pix_fmt", "yuv420p", "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-f", "mp4"])
        .arg(target)
        .stdin(Stdio::piped());
    // Watched: an interrupt kills it before removing the file it writes.
    let (child, stdin) = WatchedChild::spawn(&mut command).context("cannot start ffmpeg")?;
    {
        let mut stdin = stdin.expect("piped");
        for k in 0..animation.frames.len() {
            stdin.write_all(&animation.frame_rgb(k)?)?;
        }
        // Dropped here: ffmpeg sees the end of its input.
    }
    let status = child.wait()?;
    if !status.success() {
        bail!("ffmpeg failed ({status}) while encoding the MP4");
    }
    Ok(())
}
