//! Heat maps of values on a regular grid (the flip fractal), rendered with plotters: the
//! perceptually uniform viridis colour map with a colour bar ticked at round values, or a
//! few discrete categories with a legend.

use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;

use crate::figure::{draw_error, encode_png, ensure_font};
use crate::ticks::Axis;
use crate::{Error, Rgb};

/// A grid of values as an image: `values` holds `ny` rows of `nx` cells, the first row at
/// the bottom (low y), the first cell of a row at the left (low x).
#[derive(Debug, Clone)]
pub struct Heatmap {
    /// Title.
    pub title: String,
    /// x-axis label, with units.
    pub x_label: String,
    /// y-axis label, with units.
    pub y_label: String,
    /// Colour-bar label, with units.
    pub bar_label: String,
    /// x range of the grid's outer edges.
    pub x: (f64, f64),
    /// y range of the grid's outer edges.
    pub y: (f64, f64),
    /// Cells per row.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
    /// The values; NaN cells take `nan_color`.
    pub values: Vec<f64>,
    /// Colour by log₁₀ of the value (for positive values spanning decades).
    pub log: bool,
    /// Colour of NaN cells.
    pub nan_color: Rgb,
    /// Empty for a continuous colour map with a colour bar; otherwise the values are
    /// category indices (0, 1, …) drawn in these colours, with a legend of these names.
    pub categories: Vec<(String, Rgb)>,
}

impl Heatmap {
    /// The finite (positive on a log scale) range of the values.
    fn range(&self) -> Result<(f64, f64), Error> {
        if !self.categories.is_empty() {
            return Ok((0.0, self.categories.len() as f64));
        }
        let mut r = (f64::INFINITY, f64::NEG_INFINITY);
        for &v in self.values.iter().filter(|v| v.is_finite() && (!self.log || **v > 0.0)) {
            r = (r.0.min(v), r.1.max(v));
        }
        if !r.0.is_finite() {
            return Err(Error::Empty(self.title.clone()));
        }
        if r.0 == r.1 {
            r.1 = r.0 + if r.0 == 0.0 { 1.0 } else { r.0.abs() * 1e-3 };
        }
        Ok(if self.log { (r.0.log10(), r.1.log10()) } else { r })
    }

    /// The image as PNG bytes (about 900 × 760 pixels).
    pub fn png(&self) -> Result<Vec<u8>, Error> {
        assert_eq!(self.values.len(), self.nx * self.ny, "nx * ny values");
        let (w, h) = (900u32, 760u32);
        let mut rgb = vec![255u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
            self.draw(&root)?;
            root.present().map_err(draw_error)?;
        }
        encode_png(&rgb, w, h)
    }

    /// The image as an SVG document (one rectangle per cell: large for large grids).
    pub fn svg(&self) -> Result<String, Error> {
        assert_eq!(self.values.len(), self.nx * self.ny, "nx * ny values");
        let mut out = String::new();
        {
            let root = SVGBackend::with_string(&mut out, (900, 760)).into_drawing_area();
            self.draw(&root)?;
            root.present().map_err(draw_error)?;
        }
        Ok(out)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, plotters::coord::Shift>) -> Result<(), Error> {
        ensure_font();
        root.fill(&WHITE).map_err(draw_error)?;
        let (lo, hi) = self.range()?;
        let colour = |v: f64| -> RGBColor {
            if !self.categories.is_empty() {
                let i = v as usize;
                return if v.is_finite() && v >= 0.0 && i < self.categories.len() {
                    self.categories[i].1
                } else {
                    self.nan_color
                };
            }
            if !v.is_finite() || (self.log && v <= 0.0) {
                return self.nan_color;
            }
            let s = if self.log { v.log10() } else { v };
            // Normalised here, in f64 and halved (so that s − lo cannot overflow for values
            // near ±f64::MAX): plotters normalises in f32, where such values are infinite,
            // and panics on the NaN that follows. A flat range gives its middle colour.
            let span = 0.5 * hi - 0.5 * lo;
            let t = if span > 0.0 { ((0.5 * s - 0.5 * lo) / span).clamp(0.0, 1.0) } else { 0.5 };
            if t.is_nan() {
                return self.nan_color;
            }
            ViridisRGB.get_color_normalized(t as f32, 0.0, 1.0)
        };
        let root = root.titled(&self.title, ("sans-serif", 24)).map_err(draw_error)?;
        let side = if self.categories.is_empty() { 150 } else { 190 };
        let (main, bar) = root.split_horizontally(root.dim_in_pixel().0 - side);
        let (xa, ya) = (Axis::new(self.x.0..self.x.1, false), Axis::new(self.y.0..self.y.1, false));
        let (xf, yf) = (xa.clone(), ya.clone());
        let mut chart = ChartBuilder::on(&main)
            .margin(12)
            .x_label_area_size(52)
            .y_label_area_size(70)
            .build_cartesian_2d(xa, ya)
            .map_err(draw_error)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_labels(8)
            .y_labels(8)
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 17))
            .x_label_formatter(&|v| xf.label(*v))
            .y_label_formatter(&|v| yf.label(*v))
            .draw()
            .map_err(draw_error)?;
        let (dx, dy) = ((self.x.1 - self.x.0) / self.nx as f64, (self.y.1 - self.y.0) / self.ny as f64);
        chart
            .draw_series(self.values.iter().enumerate().map(|(k, &v)| {
                let (i, j) = ((k % self.nx) as f64, (k / self.nx) as f64);
                let (x0, y0) = (self.x.0 + i * dx, self.y.0 + j * dy);
                Rectangle::new([(x0, y0), (x0 + dx, y0 + dy)], colour(v).filled())
            }))
            .map_err(draw_error)?;

        if !self.categories.is_empty() {
            // A legend of swatches, one per category.
            // Drawing-area coordinates are relative to the column.
            let (x0, y0) = (8, 40);
            let font = ("sans-serif", 15).into_font().color(&BLACK);
            bar.draw(&Text::new(self.bar_label.as_str(), (x0, y0 - 20), font.clone())).map_err(draw_error)?;
            let mut rows: Vec<(String, Rgb)> = self.categories.clone();
            if self.values.iter().any(|v| !v.is_finite()) {
                rows.push(("no value".into(), self.nan_color));
            }
            for (k, (name, c)) in rows.iter().enumerate() {
                let (x, y) = (x0, y0 + 8 + 28 * k as i32);
                bar.draw(&Rectangle::new([(x, y), (x + 22, y + 18)], c.filled())).map_err(draw_error)?;
                bar.draw(&Rectangle::new([(x, y), (x + 22, y + 18)], RGBColor(120, 120, 120)))
                    .map_err(draw_error)?;
                bar.draw(&Text::new(name.as_str(), (x + 30, y + 1), font.clone())).map_err(draw_error)?;
            }
            return Ok(());
        }

        // The colour bar: a column of 256 bands over the value range, ticked at round values
        // (1, 2, 5 × 10ᵏ on a log scale, nice numbers on a linear one).
        let bar_axis =
            if self.log { Axis::new(10f64.powf(lo)..10f64.powf(hi), true) } else { Axis::new(lo..hi, false) };
        let bar_format = bar_axis.clone();
        let mut bar_chart = ChartBuilder::on(&bar)
            .margin_top(12)
            .margin_bottom(64)
            .margin_right(12)
            .y_label_area_size(80)
            .build_cartesian_2d(0.0..1.0, bar_axis)
            .map_err(draw_error)?;
        bar_chart
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_desc(&self.bar_label)
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .y_label_formatter(&|v| bar_format.label(*v))
            .draw()
            .map_err(draw_error)?;
        let bands = 256;
        let value = |s: f64| if self.log { 10f64.powf(s) } else { s };
        bar_chart
            .draw_series((0..bands).map(|b| {
                // Halved, as the cells' colours are, so that hi − lo cannot overflow.
                let at = |f: f64| 2.0 * (0.5 * lo + (0.5 * hi - 0.5 * lo) * f);
                let (s0, s1) = (at(b as f64 / bands as f64), at((b + 1) as f64 / bands as f64));
                let c = ViridisRGB.get_color_normalized(((b as f64 + 0.5) / bands as f64) as f32, 0.0, 1.0);
                Rectangle::new([(0.0, value(s0)), (1.0, value(s1))], c.filled())
            }))
            .map_err(draw_error)?;
        Ok(())
    }
}
