//! Line and scatter figures as data, rendered with plotters.

use std::sync::Once;

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use crate::ticks::Axis;
use crate::{Error, Rgb};

/// Axis scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Scale {
    /// Linear.
    #[default]
    Linear,
    /// Base-10 logarithmic, labelled at every power of ten; non-positive values are left out.
    Log,
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Kind {
    /// A line in the series' pattern; a styled series (see [`Figure::with_style`]) also
    /// carries a few of its markers along it, so that it can be told apart in grey.
    #[default]
    Line,
    /// A dashed line.
    Dashed,
    /// Markers only.
    Markers,
    /// A line with a marker at every point.
    LineMarkers,
    /// Small dots, for clouds of many points.
    Dots,
    /// A guide to the eye, not data (a slope of reference): a thin dashed line in the
    /// series' colour, its label written on the plot beside the line's last point instead of
    /// in the legend.
    Guide,
}

/// Where the legend goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Legend {
    /// Chosen from the data: the first place (upper right, upper left, lower right, lower
    /// left, halfway down the right side, the left side) where the legend covers no point
    /// or line of any series; if every one would, [`Legend::Outside`].
    #[default]
    Auto,
    /// In a column to the right of the plot; the canvas is widened by that column.
    Outside,
    /// Top right corner.
    UpperRight,
    /// Bottom right corner.
    LowerRight,
    /// Top left corner.
    UpperLeft,
    /// Bottom left corner.
    LowerLeft,
}

/// A line pattern.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Dash {
    /// Solid.
    #[default]
    Solid,
    /// Dashes of 10 pixels.
    Dashed,
    /// Dots.
    Dotted,
}

/// A marker shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Marker {
    /// Filled circle.
    #[default]
    Circle,
    /// Filled square.
    Square,
    /// Filled triangle, point up.
    TriangleUp,
    /// Filled diamond.
    Diamond,
    /// Filled triangle, point down.
    TriangleDown,
    /// Plus sign.
    Plus,
    /// Diagonal cross.
    Cross,
}

/// The marker shapes, in the order styles take them.
pub const MARKERS: [Marker; 7] = [
    Marker::Circle,
    Marker::Square,
    Marker::TriangleUp,
    Marker::Diamond,
    Marker::TriangleDown,
    Marker::Plus,
    Marker::Cross,
];

/// Colour, marker and line pattern of a series.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Style {
    /// Colour.
    pub color: Rgb,
    /// Marker shape.
    pub marker: Marker,
    /// Line pattern.
    pub dash: Dash,
}

/// One labelled series of (x, y) points.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend label; empty for none.
    pub label: String,
    /// Colour.
    pub color: Rgb,
    /// How it is drawn.
    pub kind: Kind,
    /// The points; non-finite ones are left out.
    pub points: Vec<(f64, f64)>,
    /// Marker shape (for markers, and along lines of styled series).
    pub marker: Option<Marker>,
    /// Line pattern.
    pub dash: Dash,
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
    /// Size in pixels (PNG) or user units (SVG) of the chart; a legend outside widens it.
    pub size: (u32, u32),
    /// Legend position.
    pub legend: Legend,
    /// A bar chart drawn instead of the series (see `From<Bars>`), so that every figure
    /// goes through the same writers.
    pub bars: Option<Box<crate::Bars>>,
    /// A second chart drawn below this one in the same image (see [`Figure::with_panel`]).
    pub panel: Option<Box<Figure>>,
}

impl From<crate::Bars> for Figure {
    /// The bar chart as a figure.
    fn from(bars: crate::Bars) -> Self {
        let mut f = Figure::new(bars.title.clone(), "", bars.value_label.clone());
        f.bars = Some(Box::new(bars));
        f
    }
}

/// Where the legend was put.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Placement {
    /// `top`: Some(true) top, Some(false) bottom, None halfway.
    Corner {
        right: bool,
        top: Option<bool>,
    },
    Outside,
}

const LEGEND_FONT: u32 = 15;
const ROW: i32 = 22;
const SAMPLE: i32 = 36;

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
            legend: Legend::Auto,
            bars: None,
            panel: None,
        }
    }

    /// With `panel` drawn below the chart, in the same image, with its own title, axes and
    /// legend: a closer look at part of the data (a run that stopped early, over its own
    /// time span, where the main chart's axis squeezes it into a streak).
    pub fn with_panel(mut self, panel: Figure) -> Self {
        self.panel = Some(Box::new(panel));
        self
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

    /// Adds a series in one colour: solid (or, for [`Kind::Dashed`] and [`Kind::Guide`],
    /// dashed) lines, round markers.
    pub fn with(mut self, label: impl Into<String>, color: Rgb, kind: Kind, points: Vec<(f64, f64)>) -> Self {
        let marker = matches!(kind, Kind::Markers | Kind::LineMarkers).then_some(Marker::Circle);
        let dash = if matches!(kind, Kind::Dashed | Kind::Guide) { Dash::Dashed } else { Dash::Solid };
        self.series.push(Series { label: label.into(), color, kind, points, marker, dash });
        self
    }

    /// Adds a series in a full style (a method's, from [`crate::method_style`]): its colour,
    /// its line pattern, and its marker — at every point, or a few along a [`Kind::Line`].
    pub fn with_style(
        mut self,
        label: impl Into<String>,
        style: Style,
        kind: Kind,
        points: Vec<(f64, f64)>,
    ) -> Self {
        let dash = if kind == Kind::Dashed && style.dash == Dash::Solid { Dash::Dashed } else { style.dash };
        self.series.push(Series {
            label: label.into(),
            color: style.color,
            kind,
            points,
            marker: Some(style.marker),
            dash,
        });
        self
    }

    /// The figure as PNG bytes.
    pub fn png(&self) -> Result<Vec<u8>, Error> {
        if let Some(bars) = &self.bars {
            return bars.png();
        }
        let (rgb, w, h) = self.rgb()?;
        let Some(panel) = &self.panel else {
            return encode_png(&rgb, w, h);
        };
        // The panel below the chart, both left-aligned on a white canvas as wide as the wider.
        let (prgb, pw, ph) = panel.rgb()?;
        let width = w.max(pw);
        let mut canvas = vec![255u8; (width * (h + ph) * 3) as usize];
        for (rows, (cw, y0)) in [(&rgb, (w, 0)), (&prgb, (pw, h))] {
            for (k, row) in rows.chunks_exact((cw * 3) as usize).enumerate() {
                let at = ((y0 as usize + k) * width as usize) * 3;
                canvas[at..at + row.len()].copy_from_slice(row);
            }
        }
        encode_png(&canvas, width, h + ph)
    }

    /// The chart alone (without its panel) as RGB bytes, with its width and height.
    fn rgb(&self) -> Result<(Vec<u8>, u32, u32), Error> {
        let (placement, extra) = self.placement()?;
        let (w, h) = (self.size.0 + extra, self.size.1);
        let mut rgb = vec![255u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
            self.draw(&root, placement)?;
            root.present().map_err(|e| Error::Draw(e.to_string()))?;
        }
        Ok((rgb, w, h))
    }

    /// The figure as an SVG document.
    pub fn svg(&self) -> Result<String, Error> {
        if let Some(bars) = &self.bars {
            return bars.svg();
        }
        let main = self.svg_chart()?;
        let Some(panel) = &self.panel else {
            return Ok(main);
        };
        // Each chart is an <svg> of its own size; the panel's is nested below the chart's.
        let size = |svg: &str, attr: &str| -> u32 {
            svg.split(&format!("{attr}=\""))
                .nth(1)
                .and_then(|v| v.split('"').next()?.parse().ok())
                .unwrap_or(0)
        };
        let below = panel.svg_chart()?;
        let (w, h) = (size(&main, "width"), size(&main, "height"));
        let (pw, ph) = (size(&below, "width"), size(&below, "height"));
        let (width, height) = (w.max(pw), h + ph);
        Ok(format!(
            "<svg width=\"{width}\" height=\"{height}\" viewBox=\"0 0 {width} {height}\" xmlns=\"http://www.w3.org/2000/svg\">\n{main}\n<g transform=\"translate(0,{h})\">\n{below}\n</g>\n</svg>\n"
        ))
    }

    /// The chart alone (without its panel) as an SVG document.
    fn svg_chart(&self) -> Result<String, Error> {
        let (placement, extra) = self.placement()?;
        let mut out = String::new();
        {
            let root =
                SVGBackend::with_string(&mut out, (self.size.0 + extra, self.size.1)).into_drawing_area();
            self.draw(&root, placement)?;
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

    fn axes(&self) -> Result<(Axis, Axis), Error> {
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
        let (x, y) = (pad(xs, self.x_scale), pad(ys, self.y_scale));
        Ok((Axis::new(x, self.x_scale == Scale::Log), Axis::new(y, self.y_scale == Scale::Log)))
    }

    /// The series in the legend: those with a label, guides aside (their label is on the
    /// plot).
    fn labelled(&self) -> impl Iterator<Item = &Series> {
        self.series.iter().filter(|s| !s.label.is_empty() && s.kind != Kind::Guide)
    }

    /// The legend's entries, in order.
    pub fn legend_entries(&self) -> Vec<&str> {
        self.labelled().map(|s| s.label.as_str()).collect()
    }

    /// The legend's size in pixels.
    fn legend_size<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(i32, i32), Error> {
        let font = ("sans-serif", LEGEND_FONT).into_font();
        let mut width = 0;
        let mut rows = 0;
        for s in self.labelled() {
            width = width
                .max(area.estimate_text_size(&s.label, &font.clone().into()).map_err(draw_error)?.0 as i32);
            rows += 1;
        }
        Ok((8 + SAMPLE + 8 + width + 10, 6 + rows * ROW + 4))
    }

    /// Where the legend goes, and how much wider than `size` the canvas must be for it.
    /// [`Legend::Auto`] lays the chart out on a scratch canvas to see where the data fall.
    fn placement(&self) -> Result<(Placement, u32), Error> {
        ensure_font();
        let (w, h) = self.size;
        let mut scratch = vec![255u8; (w * h * 3) as usize];
        let root = BitMapBackend::with_buffer(&mut scratch, (w, h)).into_drawing_area();
        let (lw, lh) = self.legend_size(&root)?;
        let corner = |right, top: bool| Ok((Placement::Corner { right, top: Some(top) }, 0));
        match self.legend {
            _ if self.labelled().next().is_none() => return corner(true, true),
            Legend::UpperRight => return corner(true, true),
            Legend::UpperLeft => return corner(false, true),
            Legend::LowerRight => return corner(true, false),
            Legend::LowerLeft => return corner(false, false),
            Legend::Outside => return Ok((Placement::Outside, (lw + 16) as u32)),
            Legend::Auto => {}
        }
        let (xa, ya) = self.axes()?;
        let inner = root.titled(&self.title, ("sans-serif", 24)).map_err(draw_error)?;
        let chart = self.chart(&inner, xa, ya)?;
        let (xr, yr) = chart.plotting_area().get_pixel_range();
        // Every series as pixels, lines sampled every few pixels between their points.
        let mut pixels = Vec::new();
        for s in &self.series {
            let mut last: Option<(i32, i32)> = None;
            let line = !matches!(s.kind, Kind::Markers | Kind::Dots);
            for p in self.visible(s) {
                let q = chart.backend_coord(&p);
                if let (true, Some(a)) = (line, last) {
                    let n = ((q.0 - a.0).abs().max((q.1 - a.1).abs()) / 3).min(400);
                    for k in 1..n {
                        let f = k as f64 / n as f64;
                        pixels.push((
                            a.0 + ((q.0 - a.0) as f64 * f) as i32,
                            a.1 + ((q.1 - a.1) as f64 * f) as i32,
                        ));
                    }
                }
                pixels.push(q);
                last = Some(q);
            }
        }
        let spots = [
            (true, Some(true)),
            (false, Some(true)),
            (true, Some(false)),
            (false, Some(false)),
            (true, None),
            (false, None),
        ];
        for (right, top) in spots {
            let (x0, y0) = legend_origin(&xr, &yr, (lw, lh), right, top);
            let m = 6;
            let covered = pixels
                .iter()
                .any(|p| p.0 >= x0 - m && p.0 <= x0 + lw + m && p.1 >= y0 - m && p.1 <= y0 + lh + m);
            if !covered {
                return Ok((Placement::Corner { right, top }, 0));
            }
        }
        Ok((Placement::Outside, (lw + 16) as u32))
    }

    /// The chart on `area`: margins, label areas and the coordinates.
    fn chart<'a, DB: DrawingBackend>(
        &self,
        area: &'a DrawingArea<DB, Shift>,
        xa: Axis,
        ya: Axis,
    ) -> Result<ChartContext<'a, DB, Cartesian2d<Axis, Axis>>, Error> {
        ChartBuilder::on(area)
            .margin(16)
            .x_label_area_size(52)
            .y_label_area_size(92)
            .build_cartesian_2d(xa, ya)
            .map_err(draw_error)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        placement: Placement,
    ) -> Result<(), Error> {
        ensure_font();
        root.fill(&WHITE).map_err(draw_error)?;
        let (xa, ya) = self.axes()?;
        let inner = root.titled(&self.title, ("sans-serif", 24)).map_err(draw_error)?;
        let (plot, side) = match placement {
            Placement::Outside => {
                let (a, b) = inner.split_horizontally(self.size.0);
                (a, Some(b))
            }
            Placement::Corner { .. } => (inner, None),
        };
        let (xf, yf) = (xa.clone(), ya.clone());
        let mut chart = self.chart(&plot, xa, ya)?;
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 17))
            .light_line_style(RGBColor(238, 238, 238))
            .bold_line_style(RGBColor(212, 212, 212))
            .x_label_formatter(&|v| xf.label(*v))
            .y_label_formatter(&|v| yf.label(*v))
            .draw()
            .map_err(draw_error)?;
        for (index, s) in self.series.iter().enumerate() {
            let points: Vec<(f64, f64)> = self.visible(s).collect();
            let width = if s.kind == Kind::Guide { 1 } else { 2 };
            let line = ShapeStyle { color: s.color.to_rgba(), filled: false, stroke_width: width };
            if matches!(s.kind, Kind::Line | Kind::Dashed | Kind::LineMarkers | Kind::Guide) {
                draw_line(&mut chart, points.clone(), s.dash, line)?;
            }
            let pixel = |p: &(f64, f64)| chart.backend_coord(p);
            match (s.kind, s.marker) {
                (Kind::Dots, _) => chart
                    .draw_series(points.iter().map(|p| Circle::new(*p, 1, s.color.filled())))
                    .map(|_| ())
                    .map_err(draw_error)?,
                (Kind::Markers | Kind::LineMarkers, m) => {
                    for p in &points {
                        draw_marker(root, pixel(p), m.unwrap_or_default(), 5, s.color)?;
                    }
                }
                (Kind::Line | Kind::Dashed, Some(m)) => {
                    // A few markers along the line, staggered between series so that they
                    // do not sit on top of each other.
                    let n = points.len();
                    if n > 1 {
                        let every = (n / 8).max(1);
                        let offset = (index * every / 5) % every;
                        for p in points.iter().skip(offset).step_by(every) {
                            draw_marker(root, pixel(p), m, 5, s.color)?;
                        }
                    }
                }
                (Kind::Line | Kind::Dashed, None) => {}
                (Kind::Guide, _) => {
                    // The label halfway along the line (in its points, which a guide spaces
                    // evenly on the axes), above and left of it, on a white ground so that it
                    // stays readable over data, in a grey darker than the line.
                    if let (false, Some(mid)) = (s.label.is_empty(), points.get(points.len() / 2)) {
                        let (x, y) = pixel(mid);
                        let font = ("sans-serif", 14).into_font();
                        let (w, h) =
                            root.estimate_text_size(&s.label, &font.clone().into()).map_err(draw_error)?;
                        let (x0, y0) = (x - w as i32 - 6, y - h as i32 - 6);
                        root.draw(&Rectangle::new(
                            [(x0 - 2, y0 - 1), (x0 + w as i32 + 2, y0 + h as i32 + 1)],
                            WHITE.mix(0.85).filled(),
                        ))
                        .map_err(draw_error)?;
                        let font = font.color(&RGBColor(90, 90, 90));
                        root.draw(&Text::new(s.label.as_str(), (x0, y0), font)).map_err(draw_error)?;
                    }
                }
            }
        }
        if self.labelled().next().is_none() {
            return Ok(());
        }
        let (lw, lh) = self.legend_size(root)?;
        let (x0, y0) = match placement {
            Placement::Corner { right, top } => {
                let (xr, yr) = chart.plotting_area().get_pixel_range();
                legend_origin(&xr, &yr, (lw, lh), right, top)
            }
            Placement::Outside => {
                let (xr, _) = side.as_ref().map(|s| s.get_pixel_range()).unwrap_or((0..0, 0..0));
                let (_, yr) = chart.plotting_area().get_pixel_range();
                (xr.start + 4, yr.start)
            }
        };
        root.draw(&Rectangle::new([(x0, y0), (x0 + lw, y0 + lh)], WHITE.mix(0.92).filled()))
            .map_err(draw_error)?;
        root.draw(&Rectangle::new([(x0, y0), (x0 + lw, y0 + lh)], RGBColor(180, 180, 180)))
            .map_err(draw_error)?;
        let font = ("sans-serif", LEGEND_FONT).into_font().color(&BLACK);
        for (k, s) in self.labelled().enumerate() {
            let y = y0 + 6 + k as i32 * ROW + ROW / 2;
            let (a, b) = (x0 + 8, x0 + 8 + SAMPLE);
            let style = ShapeStyle { color: s.color.to_rgba(), filled: false, stroke_width: 3 };
            if matches!(s.kind, Kind::Line | Kind::Dashed | Kind::LineMarkers) {
                match s.dash {
                    Dash::Solid => root.draw(&PathElement::new(vec![(a, y), (b, y)], style)),
                    Dash::Dashed => root.draw(&DashedPathElement::new(vec![(a, y), (b, y)], 9, 5, style)),
                    Dash::Dotted => root.draw(&DashedPathElement::new(vec![(a, y), (b, y)], 3, 4, style)),
                }
                .map_err(draw_error)?;
            }
            match (s.kind, s.marker) {
                (Kind::Dots, _) => {
                    root.draw(&Circle::new(((a + b) / 2, y), 3, s.color.filled())).map_err(draw_error)?
                }
                (_, Some(m)) => draw_marker(root, ((a + b) / 2, y), m, 5, s.color)?,
                _ => {}
            }
            root.draw(&Text::new(s.label.as_str(), (b + 8, y - 9), font.clone())).map_err(draw_error)?;
        }
        Ok(())
    }
}

/// The top-left pixel of a legend of `size` in a corner of the plot area, or halfway
/// down one side (`top` None).
fn legend_origin(
    xr: &std::ops::Range<i32>,
    yr: &std::ops::Range<i32>,
    size: (i32, i32),
    right: bool,
    top: Option<bool>,
) -> (i32, i32) {
    let inset = 10;
    let x = if right { xr.end - inset - size.0 } else { xr.start + inset };
    let y = match top {
        Some(true) => yr.start + inset,
        Some(false) => yr.end - inset - size.1,
        None => (yr.start + yr.end - size.1) / 2,
    };
    (x, y)
}

/// A line in data coordinates, in a pattern measured in pixels.
fn draw_line<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<Axis, Axis>>,
    points: Vec<(f64, f64)>,
    dash: Dash,
    style: ShapeStyle,
) -> Result<(), Error> {
    match dash {
        Dash::Solid => chart.draw_series(LineSeries::new(points, style)).map(|_| ()),
        Dash::Dashed => chart.draw_series(DashedLineSeries::new(points, 10, 6, style)).map(|_| ()),
        Dash::Dotted => chart.draw_series(DashedLineSeries::new(points, 3, 4, style)).map(|_| ()),
    }
    .map_err(draw_error)
}

/// A marker of radius `r` pixels centred on pixel `c`.
pub(crate) fn draw_marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    c: (i32, i32),
    marker: Marker,
    r: i32,
    color: Rgb,
) -> Result<(), Error> {
    let fill = color.filled();
    let poly = |pts: &[(f64, f64)]| {
        Polygon::new(
            pts.iter()
                .map(|(x, y)| (c.0 + (x * r as f64).round() as i32, c.1 + (y * r as f64).round() as i32))
                .collect::<Vec<_>>(),
            fill,
        )
    };
    let bar = 0.38;
    match marker {
        Marker::Circle => area.draw(&Circle::new(c, r, fill)),
        Marker::Square => area.draw(&poly(&[(-0.85, -0.85), (0.85, -0.85), (0.85, 0.85), (-0.85, 0.85)])),
        Marker::TriangleUp => area.draw(&poly(&[(0.0, -1.2), (1.05, 0.75), (-1.05, 0.75)])),
        Marker::TriangleDown => area.draw(&poly(&[(0.0, 1.2), (1.05, -0.75), (-1.05, -0.75)])),
        Marker::Diamond => area.draw(&poly(&[(0.0, -1.25), (1.0, 0.0), (0.0, 1.25), (-1.0, 0.0)])),
        Marker::Plus => area.draw(&poly(&plus_outline(bar, 1.2))),
        Marker::Cross => {
            let s = std::f64::consts::FRAC_1_SQRT_2;
            let rot = |(x, y): (f64, f64)| (s * (x - y), s * (x + y));
            let pts: Vec<(f64, f64)> = plus_outline(bar, 1.35).into_iter().map(rot).collect();
            area.draw(&poly(&pts))
        }
    }
    .map_err(draw_error)
}

pub(crate) fn draw_error<E: std::fmt::Display>(e: E) -> Error {
    Error::Draw(e.to_string())
}

/// Widens a data range by 5% (a decade fraction on log axes) so nothing sits on the frame.
pub(crate) fn pad((lo, hi): (f64, f64), scale: Scale) -> std::ops::Range<f64> {
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

/// The outline of a plus sign of half-width `bar` and arm length `arm` (in marker radii),
/// corner by corner; the cross marker is the same outline turned by 45°.
fn plus_outline(bar: f64, arm: f64) -> [(f64, f64); 12] {
    [
        (-bar, -arm),
        (bar, -arm),
        (bar, -bar),
        (arm, -bar),
        (arm, bar),
        (bar, bar),
        (bar, arm),
        (-bar, arm),
        (-bar, bar),
        (-arm, bar),
        (-arm, -bar),
        (-bar, -bar),
    ]
}
