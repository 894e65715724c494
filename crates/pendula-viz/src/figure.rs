//! Line and scatter figures as data, rendered with plotters.

use std::ops::Range;
use std::sync::Once;

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use crate::{Error, Rgb};

/// Axis scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Scale {
    /// Linear.
    #[default]
    Linear,
    /// Base-10 logarithmic; non-positive values are left out.
    Log,
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Kind {
    /// A solid line.
    #[default]
    Line,
    /// A dashed line.
    Dashed,
    /// Markers only.
    Markers,
    /// A solid line with markers.
    LineMarkers,
    /// Small dots, for clouds of many points.
    Dots,
}

/// Where the legend goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Legend {
    /// Top right corner.
    #[default]
    UpperRight,
    /// Bottom right corner.
    LowerRight,
    /// Top left corner.
    UpperLeft,
    /// Bottom left corner.
    LowerLeft,
}

/// One labelled series of (x, y) points.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Colour.
    pub color: Rgb,
    /// How it is drawn.
    pub kind: Kind,
    /// The points; non-finite ones are left out.
    pub points: Vec<(f64, f64)>,
}

/// A figure: one chart with a title, labelled axes and a legend.
#[derive(Debug, Clone)]
pub struct Figure {
    /// Title above the chart.
    pub title: String,
    /// x-axis label, with units.
    pub x_label: String,
    /// y-axis label, with units.
    pub y_label: String,
    /// x-axis scale.
    pub x_scale: Scale,
    /// y-axis scale.
    pub y_scale: Scale,
    /// The series, drawn in order.
    pub series: Vec<Series>,
    /// Size in pixels (PNG) or user units (SVG).
    pub size: (u32, u32),
    /// Legend position.
    pub legend: Legend,
}

impl Figure {
    /// An empty figure of 960 × 600 pixels.
    pub fn new(title: impl Into<String>, x_label: impl Into<String>, y_label: impl Into<String>) -> Self {
        Figure {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            series: Vec::new(),
            size: (960, 600),
            legend: Legend::UpperRight,
        }
    }

    /// With the legend here.
    pub fn legend(mut self, legend: Legend) -> Self {
        self.legend = legend;
        self
    }

    /// With these axis scales.
    pub fn scales(mut self, x: Scale, y: Scale) -> Self {
        (self.x_scale, self.y_scale) = (x, y);
        self
    }

    /// Adds a series.
    pub fn with(mut self, label: impl Into<String>, color: Rgb, kind: Kind, points: Vec<(f64, f64)>) -> Self {
        self.series.push(Series { label: label.into(), color, kind, points });
        self
    }

    /// The figure as PNG bytes.
    pub fn png(&self) -> Result<Vec<u8>, Error> {
        let (w, h) = self.size;
        let mut rgb = vec![255u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
            self.draw(&root)?;
            root.present().map_err(|e| Error::Draw(e.to_string()))?;
        }
        encode_png(&rgb, w, h)
    }

    /// The figure as an SVG document.
    pub fn svg(&self) -> Result<String, Error> {
        let mut out = String::new();
        {
            let root = SVGBackend::with_string(&mut out, self.size).into_drawing_area();
            self.draw(&root)?;
            root.present().map_err(|e| Error::Draw(e.to_string()))?;
        }
        Ok(out)
    }

    /// The finite (and, on log axes, positive) points of a series.
    fn visible<'a>(&self, s: &'a Series) -> impl Iterator<Item = (f64, f64)> + 'a {
        let (xl, yl) = (self.x_scale == Scale::Log, self.y_scale == Scale::Log);
        s.points
            .iter()
            .copied()
            .filter(move |(x, y)| x.is_finite() && y.is_finite() && (!xl || *x > 0.0) && (!yl || *y > 0.0))
    }

    fn ranges(&self) -> Result<(Range<f64>, Range<f64>), Error> {
        let mut xs = (f64::INFINITY, f64::NEG_INFINITY);
        let mut ys = xs;
        for s in &self.series {
            for (x, y) in self.visible(s) {
                xs = (xs.0.min(x), xs.1.max(x));
                ys = (ys.0.min(y), ys.1.max(y));
            }
        }
        if !xs.0.is_finite() {
            return Err(Error::Empty(self.title.clone()));
        }
        Ok((pad(xs, self.x_scale), pad(ys, self.y_scale)))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, plotters::coord::Shift>) -> Result<(), Error> {
        ensure_font();
        root.fill(&WHITE).map_err(draw_error)?;
        let (xr, yr) = self.ranges()?;
        match (self.x_scale, self.y_scale) {
            (Scale::Linear, Scale::Linear) => self.chart(root, (xr.clone(), yr.clone()), xr, yr),
            (Scale::Linear, Scale::Log) => self.chart(root, (xr.clone(), yr.clone()), xr, yr.log_scale()),
            (Scale::Log, Scale::Linear) => self.chart(root, (xr.clone(), yr.clone()), xr.log_scale(), yr),
            (Scale::Log, Scale::Log) => {
                self.chart(root, (xr.clone(), yr.clone()), xr.log_scale(), yr.log_scale())
            }
        }
    }

    fn chart<DB, X, Y>(
        &self,
        root: &DrawingArea<DB, plotters::coord::Shift>,
        spans: (Range<f64>, Range<f64>),
        x: X,
        y: Y,
    ) -> Result<(), Error>
    where
        DB: DrawingBackend,
        X: AsRangedCoord<Value = f64>,
        Y: AsRangedCoord<Value = f64>,
        X::CoordDescType: ValueFormatter<f64>,
        Y::CoordDescType: ValueFormatter<f64>,
    {
        // On a linear axis, tick values within a billionth of the span of zero are zero.
        let zero = |scale: Scale, r: &Range<f64>| {
            if scale == Scale::Linear { 1e-9 * (r.end - r.start) } else { 0.0 }
        };
        let (x_zero, y_zero) = (zero(self.x_scale, &spans.0), zero(self.y_scale, &spans.1));
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 24))
            .margin(16)
            .x_label_area_size(52)
            .y_label_area_size(84)
            .build_cartesian_2d(x, y)
            .map_err(draw_error)?;
        chart
            .configure_mesh()
            .x_labels(8)
            .y_labels(10)
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 17))
            .light_line_style(RGBColor(235, 235, 235))
            .bold_line_style(RGBColor(215, 215, 215))
            .x_label_formatter(&|v| tick(*v, x_zero))
            .y_label_formatter(&|v| tick(*v, y_zero))
            .draw()
            .map_err(draw_error)?;
        for s in &self.series {
            let color = s.color;
            let line = ShapeStyle { color: color.to_rgba(), filled: false, stroke_width: 2 };
            let points: Vec<(f64, f64)> = self.visible(s).collect();
            let anno = match s.kind {
                Kind::Line => chart.draw_series(LineSeries::new(points, line)),
                Kind::Dashed => chart.draw_series(DashedLineSeries::new(points, 10, 6, line)),
                Kind::Markers => {
                    chart.draw_series(points.into_iter().map(move |p| Circle::new(p, 4, color.filled())))
                }
                Kind::Dots => {
                    chart.draw_series(points.into_iter().map(move |p| Circle::new(p, 1, color.filled())))
                }
                Kind::LineMarkers => {
                    chart.draw_series(LineSeries::new(points.clone(), line)).map_err(draw_error)?;
                    chart.draw_series(points.into_iter().map(move |p| Circle::new(p, 4, color.filled())))
                }
            }
            .map_err(draw_error)?;
            if !s.label.is_empty() {
                anno.label(&s.label).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 24, y)], ShapeStyle { stroke_width: 3, ..line })
                });
            }
        }
        if self.series.iter().any(|s| !s.label.is_empty()) {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(180, 180, 180))
                .label_font(("sans-serif", 15))
                .position(match self.legend {
                    Legend::UpperRight => SeriesLabelPosition::UpperRight,
                    Legend::LowerRight => SeriesLabelPosition::LowerRight,
                    Legend::UpperLeft => SeriesLabelPosition::UpperLeft,
                    Legend::LowerLeft => SeriesLabelPosition::LowerLeft,
                })
                .draw()
                .map_err(draw_error)?;
        }
        Ok(())
    }
}

pub(crate) fn draw_error<E: std::fmt::Display>(e: E) -> Error {
    Error::Draw(e.to_string())
}

/// Widens a data range by 5% (a decade fraction on log axes) so nothing sits on the frame.
fn pad((lo, hi): (f64, f64), scale: Scale) -> Range<f64> {
    match scale {
        Scale::Linear => {
            let span = if hi > lo { hi - lo } else { lo.abs().max(1.0) };
            lo - 0.05 * span..hi + 0.05 * span
        }
        Scale::Log => {
            let (a, b) = (lo.log10(), hi.log10());
            let span = if b > a { b - a } else { 1.0 };
            10f64.powf(a - 0.05 * span)..10f64.powf(b + 0.05 * span)
        }
    }
}

/// Tick labels: plain numbers in a moderate range, scientific notation outside it; values
/// within `zero` of 0 are 0.
pub(crate) fn tick(v: f64, zero: f64) -> String {
    let a = v.abs();
    if a <= zero {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{v:.0e}")
    } else {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// Registers the embedded DejaVu Sans as plotters' "sans-serif", once.
pub(crate) fn ensure_font() {
    static FONT: Once = Once::new();
    FONT.call_once(|| {
        register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
            .unwrap_or_else(|_| panic!("the embedded DejaVu Sans is a valid font"));
        register_font("sans-serif", FontStyle::Bold, dejavu::sans::bold())
            .unwrap_or_else(|_| panic!("the embedded DejaVu Sans Bold is a valid font"));
    });
}

/// RGB bytes to PNG bytes.
pub(crate) fn encode_png(rgb: &[u8], w: u32, h: u32) -> Result<Vec<u8>, Error> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| Error::Encode(e.to_string()))?;
    writer.write_image_data(rgb).map_err(|e| Error::Encode(e.to_string()))?;
    writer.finish().map_err(|e| Error::Encode(e.to_string()))?;
    Ok(out)
}
