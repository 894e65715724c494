//! A horizontal bar chart with named categories (one bar per method), rendered with
//! plotters: every category is listed, and one without a value says why in its note.

use plotters::prelude::*;

use crate::figure::{draw_error, encode_png, ensure_font, pad};
use crate::ticks::Axis;
use crate::{Error, Rgb, Scale};

/// One bar.
#[derive(Debug, Clone)]
pub struct Bar {
    /// The category's name, on the axis.
    pub label: String,
    /// The bar's length; `None` draws no bar, only the note.
    pub value: Option<f64>,
    /// Colour.
    pub color: Rgb,
    /// Text beside the bar (or in its place): a status such as "unstable at every step
    /// tried"; `None` prints the value.
    pub note: Option<String>,
    /// The value is where the method refuses to go, a limit of its definition, not a
    /// measured result: the bar is drawn empty and hatched (its note should say "refused").
    pub refused: bool,
}

impl Bar {
    /// A bar of `value` (none: only the note), measured, not refused.
    pub fn new(label: impl Into<String>, value: Option<f64>, color: Rgb, note: Option<String>) -> Self {
        Bar { label: label.into(), value, color, note, refused: false }
    }
}

/// A horizontal bar chart: categories from top to bottom in the order given.
#[derive(Debug, Clone)]
pub struct Bars {
    /// Title.
    pub title: String,
    /// Label of the value axis, with units.
    pub value_label: String,
    /// Value-axis scale.
    pub scale: Scale,
    /// The bars.
    pub bars: Vec<Bar>,
    /// The value range shown (a search range, say); `None` fits the values.
    pub limits: Option<(f64, f64)>,
    /// Width in pixels; the height grows with the number of bars.
    pub width: u32,
}

impl Bars {
    /// An empty chart, 960 pixels wide.
    pub fn new(title: impl Into<String>, value_label: impl Into<String>, scale: Scale) -> Self {
        Bars {
            title: title.into(),
            value_label: value_label.into(),
            scale,
            bars: Vec::new(),
            limits: None,
            width: 960,
        }
    }

    fn size(&self) -> (u32, u32) {
        (self.width, 130 + 34 * self.bars.len().max(1) as u32)
    }

    /// The chart as PNG bytes.
    pub fn png(&self) -> Result<Vec<u8>, Error> {
        let (w, h) = self.size();
        let mut rgb = vec![255u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
            self.draw(&root)?;
            root.present().map_err(draw_error)?;
        }
        encode_png(&rgb, w, h)
    }

    /// The chart as an SVG document.
    pub fn svg(&self) -> Result<String, Error> {
        let mut out = String::new();
        {
            let root = SVGBackend::with_string(&mut out, self.size()).into_drawing_area();
            self.draw(&root)?;
            root.present().map_err(draw_error)?;
        }
        Ok(out)
    }

    /// The value range: the limits, or the values padded.
    fn limits(&self) -> Result<(f64, f64), Error> {
        let log = self.scale == Scale::Log;
        let (lo, hi) = match self.limits {
            Some(l) => l,
            None => {
                let vals =
                    self.bars.iter().filter_map(|b| b.value).filter(|v| v.is_finite() && (!log || *v > 0.0));
                let r = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |r, v| (r.0.min(v), r.1.max(v)));
                if !r.0.is_finite() {
                    return Err(Error::Empty(self.title.clone()));
                }
                let p = pad(if log { r } else { (r.0.min(0.0), r.1) }, self.scale);
                (p.start, p.end)
            }
        };
        if !(lo.is_finite() && hi > lo && (!log || lo > 0.0)) {
            return Err(Error::Empty(self.title.clone()));
        }
        Ok((lo, hi))
    }

    /// The text beside bar `b`.
    fn note(b: &Bar) -> String {
        match (&b.note, b.value) {
            (Some(note), _) => note.clone(),
            (None, Some(v)) => crate::ticks::number(v),
            (None, None) => String::new(),
        }
    }

    /// The axis's right end: at least the upper limit, and far enough for each note to fit
    /// beside its bar, given the plot's width in pixels and each note's width.
    fn right_end(&self, (lo, hi): (f64, f64), plot_width: f64, widths: &[u32]) -> f64 {
        let log = self.scale == Scale::Log;
        let f = |v: f64| if log { v.log10() } else { v };
        let mut end = f(hi);
        for (b, w) in self.bars.iter().zip(widths) {
            let v = b.value.filter(|v| v.is_finite() && (!log || *v > 0.0)).map_or(lo, |v| v.clamp(lo, hi));
            let room = ((*w as f64 + 24.0) / plot_width).min(0.8);
            end = end.max(f(lo) + (f(v) - f(lo)) / (1.0 - room));
        }
        if log { 10f64.powf(end) } else { end }
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, plotters::coord::Shift>) -> Result<(), Error> {
        ensure_font();
        root.fill(&WHITE).map_err(draw_error)?;
        let (lo, hi) = self.limits()?;
        let log = self.scale == Scale::Log;
        let n = self.bars.len();
        // Category k (from the top) spans [n − k − 1, n − k]; its label sits at the centre.
        let mut ya = Axis::new(0.0..n.max(1) as f64, false);
        ya.ticks.major = (0..n).map(|k| k as f64 + 0.5).collect();
        ya.ticks.minor = Vec::new();
        let label_width = self
            .bars
            .iter()
            .map(|b| root.estimate_text_size(&b.label, &("sans-serif", 16).into_font().into()).map(|s| s.0))
            .collect::<Result<Vec<u32>, _>>()
            .map_err(draw_error)?
            .into_iter()
            .max()
            .unwrap_or(40);
        let note_font = ("sans-serif", 15).into_font();
        let widths = self
            .bars
            .iter()
            .map(|b| root.estimate_text_size(&Self::note(b), &note_font.clone().into()).map(|s| s.0))
            .collect::<Result<Vec<u32>, _>>()
            .map_err(draw_error)?;
        let plot_width = (root.dim_in_pixel().0 as f64 - label_width as f64 - 60.0).max(100.0);
        let xa = Axis::new(lo..self.right_end((lo, hi), plot_width, &widths), log);
        let xf = xa.clone();
        let root = root.titled(&self.title, ("sans-serif", 22)).map_err(draw_error)?;
        let mut chart = ChartBuilder::on(&root)
            .margin(16)
            .x_label_area_size(52)
            .y_label_area_size(label_width + 20)
            .build_cartesian_2d(xa, ya)
            .map_err(draw_error)?;
        let names: Vec<&str> = self.bars.iter().map(|b| b.label.as_str()).collect();
        chart
            .configure_mesh()
            .disable_y_mesh()
            .x_desc(&self.value_label)
            .label_style(("sans-serif", 16))
            .axis_desc_style(("sans-serif", 17))
            .light_line_style(RGBColor(238, 238, 238))
            .bold_line_style(RGBColor(212, 212, 212))
            .x_label_formatter(&|v| xf.label(*v))
            .y_label_formatter(&|v| {
                let k = v.floor() as usize;
                if k < n { names[n - 1 - k].to_owned() } else { String::new() }
            })
            .draw()
            .map_err(draw_error)?;
        let font = ("sans-serif", 15).into_font().color(&BLACK);
        for (k, b) in self.bars.iter().enumerate() {
            let y = (n - 1 - k) as f64;
            let end = b.value.filter(|v| v.is_finite() && (!log || *v > 0.0)).map(|v| v.clamp(lo, hi));
            match end {
                Some(v) if b.refused => {
                    // An outline with diagonal hatching: a limit, not a result.
                    chart
                        .draw_series(std::iter::once(Rectangle::new(
                            [(lo, y + 0.18), (v, y + 0.82)],
                            ShapeStyle { color: b.color.to_rgba(), filled: false, stroke_width: 2 },
                        )))
                        .map_err(draw_error)?;
                    let base = root.get_base_pixel();
                    let (a, c) = (chart.backend_coord(&(lo, y + 0.82)), chart.backend_coord(&(v, y + 0.18)));
                    let (x0, x1, top, bottom) = (a.0 - base.0, c.0 - base.0, a.1 - base.1, c.1 - base.1);
                    let height = bottom - top;
                    let style = ShapeStyle { color: b.color.to_rgba(), filled: false, stroke_width: 1 };
                    // Lines rising at 45° every 8 pixels, cut to the bar.
                    let mut x = x0 - height;
                    while x < x1 {
                        let (s0, s1) = ((x0 - x).max(0), (x1 - x).min(height));
                        if s1 > s0 {
                            root.draw(&PathElement::new(
                                vec![(x + s0, bottom - s0), (x + s1, bottom - s1)],
                                style,
                            ))
                            .map_err(draw_error)?;
                        }
                        x += 8;
                    }
                }
                Some(v) => {
                    chart
                        .draw_series(std::iter::once(Rectangle::new(
                            [(lo, y + 0.18), (v, y + 0.82)],
                            b.color.filled(),
                        )))
                        .map_err(draw_error)?;
                }
                None => {}
            }
            let text = Self::note(b);
            let at = chart.backend_coord(&(end.unwrap_or(lo), y + 0.5));
            root.draw(&Text::new(
                text,
                (at.0 - root.get_base_pixel().0 + 8, at.1 - root.get_base_pixel().1 - 9),
                font.clone(),
            ))
            .map_err(draw_error)?;
        }
        Ok(())
    }
}
