//! # pendula-viz
//!
//! Figures and animations of pendula's results. A [`Figure`] is data — title, axis labels
//! with units, linear or logarithmic axes, and [`Series`] — rendered to PNG or SVG bytes
//! with an embedded font (DejaVu Sans), so that output is the same on every machine.
//! [`method_color`] gives each integration method one colour, used in every figure.
//! [`Heatmap`] draws values on a grid with the viridis colour map and a colour bar.
//! [`animate`] draws anti-aliased pendulum frames and encodes them as GIF.
//!
//! Nothing here writes files: callers decide where bytes go.

pub mod animate;
mod figure;
mod heatmap;

pub use animate::{Animation, Snapshot};

pub use figure::{Figure, Kind, Legend, Scale, Series};
pub use heatmap::Heatmap;

use plotters::style::RGBColor;

/// What can go wrong while drawing or encoding.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The plotting backend failed.
    #[error("drawing failed: {0}")]
    Draw(String),
    /// PNG or GIF encoding failed.
    #[error("encoding failed: {0}")]
    Encode(String),
    /// Nothing to draw (no finite points, or a log axis with no positive values).
    #[error("nothing to draw in `{0}`: no finite points in range")]
    Empty(String),
}

/// An RGB colour.
pub type Rgb = RGBColor;

/// Black, for cells without a value (a flip fractal's "no flip").
pub const BLACK: Rgb = RGBColor(0, 0, 0);

/// Colour-blind-safe palette (Okabe & Ito, 2008), then Paul Tol's muted colours, in the
/// order methods are registered.
const PALETTE: [Rgb; 16] = [
    RGBColor(213, 94, 0),    // vermillion
    RGBColor(0, 114, 178),   // blue
    RGBColor(0, 158, 115),   // bluish green
    RGBColor(204, 121, 167), // reddish purple
    RGBColor(230, 159, 0),   // orange
    RGBColor(86, 180, 233),  // sky blue
    RGBColor(120, 94, 240),  // violet
    RGBColor(136, 34, 85),   // wine
    RGBColor(68, 170, 153),  // teal
    RGBColor(153, 153, 51),  // olive
    RGBColor(166, 86, 40),   // brown
    RGBColor(51, 34, 136),   // indigo
    RGBColor(100, 100, 100), // grey
    RGBColor(238, 51, 119),  // magenta
    RGBColor(17, 119, 51),   // dark green
    RGBColor(204, 187, 68),  // gold
];

/// Black, for exact solutions and references.
pub const REFERENCE: Rgb = RGBColor(0, 0, 0);

/// Light grey, for guide lines.
pub const GUIDE: Rgb = RGBColor(150, 150, 150);

/// The colour of a method, the same in every figure: its position in
/// [`pendula::integrator::METHODS`] picks a palette entry.
pub fn method_color(name: &str) -> Rgb {
    let i = pendula::integrator::METHODS.iter().position(|m| m.name == name).unwrap_or(PALETTE.len() - 1);
    PALETTE[i % PALETTE.len()]
}

/// The i-th colour of the palette, for series that are not methods.
pub fn palette(i: usize) -> Rgb {
    PALETTE[i % PALETTE.len()]
}
