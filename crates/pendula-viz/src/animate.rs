//! Pendulum animations: anti-aliased frames (tiny-skia) with text (plotters and the
//! embedded font), encoded as GIF, or as raw RGB frames for an external MP4 encoder.
//!
//! Each frame shows the rods and bobs of one or two pendulums (the second for comparing
//! nearby initial conditions), a fading trail of each last bob, the time, and a gauge of
//! the relative energy error on a log scale, each in its own part of the frame ([`Layout`]).

use std::borrow::Cow;

use plotters::prelude::*;
use tiny_skia::{FillRule, Paint, PathBuilder, Pixmap, Stroke, Transform};

use crate::{Error, Rgb, palette};

/// One instant: for each pendulum drawn, its link angles (rad, from the downward vertical)
/// and its relative energy error.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    /// Time, s.
    pub t: f64,
    /// Link angles of each pendulum, rad.
    pub angles: Vec<Vec<f64>>,
    /// |E − E₀| / |E₀| of each pendulum.
    pub energy_error: Vec<f64>,
}

/// An animation: geometry, snapshots, and how to draw them.
#[derive(Debug, Clone)]
pub struct Animation {
    /// Title in the top-left corner.
    pub title: String,
    /// Link lengths, m.
    pub lengths: Vec<f64>,
    /// One snapshot per frame.
    pub frames: Vec<Snapshot>,
    /// Frame size in pixels.
    pub size: (u32, u32),
    /// Frames per second.
    pub fps: u32,
    /// Frames a trail point stays visible.
    pub trail: usize,
    /// Legend labels of the pendulums.
    pub labels: Vec<String>,
}

/// The colour of the i-th pendulum.
fn color(i: usize) -> Rgb {
    palette(if i == 0 { 1 } else { 0 })
}

/// Where things go in a frame, in pixels (y down): a band at the top for the title and the
/// time, a band at the bottom for the energy gauges, and between them a square around the
/// pivot that holds the pendulum's whole reach — the sum of the rod lengths, plus a bob's
/// radius — so that no rod, bob or trail (a path of the last bob, inside the reach) ever
/// covers the text or the gauges.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Layout {
    /// The pivot.
    pub pivot: (f64, f64),
    /// Pixels per metre.
    pub scale: f64,
    /// The first pixel row below the title band.
    pub drawing_top: u32,
    /// The first pixel row of the gauge band.
    pub gauge_top: u32,
}

/// Radius of a bob, pixels.
const BOB: f64 = 9.0;
/// Height of the title band, pixels.
const TOP_BAND: u32 = 52;
/// Height of one gauge row, pixels.
const GAUGE_ROW: u32 = 22;

/// The GIF frame delays, in centiseconds (GIF's unit), for `frames` frames at `fps`: whole
/// centiseconds alternating (3, 3, 4, … for 30 fps) so that frame k ends at round(100 k / fps)
/// cs and the mean rate is exactly `fps`. Rates from 1 to 50 frames per second: a faster
/// one would need delays under 2 cs, which browsers replace by 10 cs.
pub fn gif_delays(fps: u32, frames: usize) -> Result<Vec<u16>, Error> {
    if !(1..=50).contains(&fps) {
        return Err(Error::Unsupported(format!(
            "a GIF cannot play {fps} frames per second: GIF delays are whole centiseconds and browsers slow delays under 2 cs down to 10 cs; use 1 to 50 (or MP4)"
        )));
    }
    // End of frame k in cs, rounded half up: (200 k + fps) / (2 fps).
    let end = |k: u64| (200 * k + fps as u64) / (2 * fps as u64);
    Ok((0..frames as u64).map(|k| (end(k + 1) - end(k)) as u16).collect())
}

impl Animation {
    /// The frame's layout (see [`Layout`]); an error if the frame is too small to hold the
    /// bands and a pendulum.
    pub fn layout(&self) -> Result<Layout, Error> {
        let (w, h) = self.size;
        let rows = self.frames.first().map_or(1, |f| f.energy_error.len()).max(1) as u32;
        let gauge_band = 20 + GAUGE_ROW * rows + 6;
        let drawing_top = TOP_BAND;
        let gauge_top = h.saturating_sub(gauge_band);
        let room = gauge_top.saturating_sub(drawing_top).min(w) as f64;
        let reach: f64 = self.lengths.iter().sum();
        let radius = room / 2.0 - BOB - 3.0;
        if radius < 12.0 || !(reach > 0.0 && reach.is_finite()) {
            return Err(Error::Unsupported(format!(
                "a {w}x{h} frame is too small for the title, {rows} energy gauge(s) and a pendulum: make it at least {}x{} pixels",
                w.max(2 * (12 + BOB as u32 + 3)),
                drawing_top + gauge_band + 2 * (12 + BOB as u32 + 3)
            )));
        }
        Ok(Layout {
            pivot: (w as f64 / 2.0, drawing_top as f64 + (gauge_top - drawing_top) as f64 / 2.0),
            scale: radius / reach,
            drawing_top,
            gauge_top,
        })
    }

    /// Frame `k` as RGB bytes (width × height × 3).
    pub fn frame_rgb(&self, k: usize) -> Result<Vec<u8>, Error> {
        let mut rgb = self.pendulums_rgb(k)?;
        self.text(&mut rgb, k)?;
        Ok(rgb)
    }

    /// The rods, bobs and trails of frame `k` alone, on white, as RGB bytes.
    pub fn pendulums_rgb(&self, k: usize) -> Result<Vec<u8>, Error> {
        let (w, h) = self.size;
        let layout = self.layout()?;
        let mut pixmap = Pixmap::new(w, h).ok_or_else(|| Error::Draw(format!("bad frame size {w}x{h}")))?;
        pixmap.fill(tiny_skia::Color::WHITE);
        let (scale, pivot) = (layout.scale, layout.pivot);
        // Screen coordinates of the joints of pendulum i at frame j (y down on screen).
        let joints = |i: usize, j: usize| {
            let mut p = pivot;
            let mut out = vec![p];
            for (theta, l) in self.frames[j].angles[i].iter().zip(&self.lengths) {
                p = (p.0 + scale * l * theta.sin(), p.1 + scale * l * theta.cos());
                out.push(p);
            }
            out
        };
        let pendulums = self.frames[k].angles.len();
        for i in 0..pendulums {
            let c = color(i);
            let first = k.saturating_sub(self.trail);
            for j in first..k {
                let (a, b) = (joints(i, j), joints(i, j + 1));
                let (a, b) = (a[a.len() - 1], b[b.len() - 1]);
                let age = (k - j) as f64 / self.trail.max(1) as f64;
                let mut paint = Paint::default();
                paint.set_color_rgba8(c.0, c.1, c.2, (200.0 * (1.0 - age)).round() as u8);
                let mut pb = PathBuilder::new();
                pb.move_to(a.0 as f32, a.1 as f32);
                pb.line_to(b.0 as f32, b.1 as f32);
                if let Some(path) = pb.finish() {
                    let stroke = Stroke { width: 2.0, ..Stroke::default() };
                    pixmap.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
                }
            }
        }
        for i in 0..pendulums {
            let c = color(i);
            let pts = joints(i, k);
            let mut rod = Paint::default();
            rod.set_color_rgba8(40, 40, 40, 255);
            let mut pb = PathBuilder::new();
            pb.move_to(pts[0].0 as f32, pts[0].1 as f32);
            for p in &pts[1..] {
                pb.line_to(p.0 as f32, p.1 as f32);
            }
            if let Some(path) = pb.finish() {
                let stroke = Stroke { width: 3.0, ..Stroke::default() };
                pixmap.stroke_path(&path, &rod, &stroke, Transform::identity(), None);
            }
            let mut bob = Paint::default();
            bob.set_color_rgba8(c.0, c.1, c.2, 255);
            for p in &pts[1..] {
                if let Some(circle) = PathBuilder::from_circle(p.0 as f32, p.1 as f32, BOB as f32) {
                    pixmap.fill_path(&circle, &bob, FillRule::Winding, Transform::identity(), None);
                }
            }
        }
        let mut pivot_paint = Paint::default();
        pivot_paint.set_color_rgba8(0, 0, 0, 255);
        if let Some(dot) = PathBuilder::from_circle(pivot.0 as f32, pivot.1 as f32, 4.0) {
            pixmap.fill_path(&dot, &pivot_paint, FillRule::Winding, Transform::identity(), None);
        }
        // Drop alpha: the background is opaque white, so the pixels are already composited.
        Ok(pixmap.data().chunks(4).flat_map(|p| [p[0], p[1], p[2]]).collect())
    }

    /// Title and time in the top band, and in the bottom band one gauge per pendulum — its
    /// colour, its relative energy error on a log scale, its label.
    fn text(&self, rgb: &mut [u8], k: usize) -> Result<(), Error> {
        crate::figure::ensure_font();
        let (w, h) = self.size;
        let layout = self.layout()?;
        let frame = &self.frames[k];
        let root = BitMapBackend::with_buffer(rgb, (w, h)).into_drawing_area();
        let draw = |e: Result<(), DrawingAreaErrorKind<_>>| e.map_err(|e| Error::Draw(e.to_string()));
        let style = ("sans-serif", 16).into_font().color(&BLACK);
        draw(root.draw_text(&self.title, &style, (10, 8)))?;
        draw(root.draw_text(&format!("t = {:.2} s", frame.t), &style, (10, 30)))?;
        // Gauge: log₁₀ of the relative energy error from 10⁻¹² (empty) to 1 (full).
        let small = ("sans-serif", 13).into_font().color(&RGBColor(60, 60, 60));
        let top = layout.gauge_top as i32;
        draw(root.draw(&PathElement::new(vec![(0, top), (w as i32, top)], RGBColor(220, 220, 220))))?;
        draw(root.draw_text("relative energy error, 10⁻¹² … 1 (log scale)", &small, (10, top + 4)))?;
        let (gx, gw) = (10, (w as i32 / 4).clamp(40, 160));
        for (i, err) in frame.energy_error.iter().enumerate() {
            let y = top + 22 + GAUGE_ROW as i32 * i as i32;
            let fill = ((err.max(1e-16).log10() + 12.0) / 12.0).clamp(0.0, 1.0);
            draw(root.draw(&Rectangle::new([(gx, y), (gx + gw, y + 12)], RGBColor(120, 120, 120))))?;
            let end = gx + (fill * gw as f64).round() as i32;
            draw(root.draw(&Rectangle::new([(gx, y), (end, y + 12)], color(i).filled())))?;
            let label = self.labels.get(i).map_or("", String::as_str);
            let text = format!("{}   {label}", crate::ticks::label(*err, err / 10.0, false));
            draw(root.draw_text(&text, &("sans-serif", 14).into_font().color(&BLACK), (gx + gw + 8, y - 2)))?;
        }
        root.present().map_err(|e| Error::Draw(e.to_string()))?;
        Ok(())
    }

    /// The animation as a looping GIF, its frame delays from [`gif_delays`] (an error for a
    /// frame rate outside 1 to 50 per second). Colours map to a fixed palette (a 6×6×6 colour cube
    /// and a 40-step grey ramp), so encoding is fast and deterministic.
    pub fn gif(&self) -> Result<Vec<u8>, Error> {
        let (w, h) = self.size;
        let palette = fixed_palette();
        let mut out = Vec::new();
        {
            let encode = |e: gif::EncodingError| Error::Encode(e.to_string());
            let mut encoder = gif::Encoder::new(&mut out, w as u16, h as u16, &palette).map_err(encode)?;
            encoder.set_repeat(gif::Repeat::Infinite).map_err(encode)?;
            let delays = gif_delays(self.fps, self.frames.len())?;
            self.layout()?;
            for (k, &delay) in delays.iter().enumerate() {
                let rgb = self.frame_rgb(k)?;
                let indices: Vec<u8> = rgb.chunks(3).map(|p| palette_index(p[0], p[1], p[2])).collect();
                let frame = gif::Frame {
                    width: w as u16,
                    height: h as u16,
                    delay,
                    buffer: Cow::Owned(indices),
                    ..gif::Frame::default()
                };
                encoder.write_frame(&frame).map_err(encode)?;
            }
        }
        Ok(out)
    }
}

/// 216 cube colours (levels 0, 51, …, 255) then 40 greys.
fn fixed_palette() -> Vec<u8> {
    let mut p = Vec::with_capacity(256 * 3);
    for r in 0..6u8 {
        for g in 0..6u8 {
            for b in 0..6u8 {
                p.extend([r * 51, g * 51, b * 51]);
            }
        }
    }
    for i in 0..40u32 {
        let v = (i * 255 / 39) as u8;
        p.extend([v, v, v]);
    }
    p
}

/// Nearest palette entry: the grey ramp for near-grey pixels (anti-aliased edges on white),
/// the colour cube otherwise.
fn palette_index(r: u8, g: u8, b: u8) -> u8 {
    let (max, min) = (r.max(g).max(b), r.min(g).min(b));
    if max - min < 12 {
        let mean = (r as u32 + g as u32 + b as u32) / 3;
        216 + ((mean * 39 + 127) / 255) as u8
    } else {
        let q = |v: u8| (v as u32 + 25) / 51;
        (q(r) * 36 + q(g) * 6 + q(b)) as u8
    }
}
