//! # pendula-viz
//!
//! Figures and animations of pendula's results. A [`Figure`] is data — title, axis labels
//! with units, linear or logarithmic axes, and [`Series`] — rendered to PNG or SVG bytes
//! with an embedded font (DejaVu Sans), so that output is the same on every machine.
//! [`method_style`] gives each integration method one colour, marker and line pattern,
//! used in every figure; [`pretty`] and [`axis_label`] turn catalogue names and units into
//! symbols (θ₁, ω₂, kg m²/s). The legend goes where it covers no data.
//! [`Bars`] is a labelled bar chart (one bar per method).
//! [`Heatmap`] draws values on a grid with the viridis colour map and a colour bar.
//! [`animate`] draws anti-aliased pendulum frames and encodes them as GIF.
//!
//! Nothing here writes files: callers decide where bytes go.
//!
//! # The modules
//!
//! Figures: `crates/pendula-viz/src/figure.rs` holds `Figure` (title, labelled axes, linear or log
//! scales, series) rendered by plotters with the embedded DejaVu Sans; its legend goes, by default,
//! in the first corner where it covers no data, else in a column outside the plot (`Legend::Auto`,
//! decided by laying the chart out on a scratch canvas). `crates/pendula-viz/src/ticks.rs` makes
//! the ticks of every axis (a label at each power of ten on log axes, 1-2-5 × 10ᵏ or nice numbers
//! on shorter spans) and the plotters coordinate that uses them; `crates/pendula-viz/src/bars.rs`
//! holds `Bars` (a labelled horizontal bar chart with a note per bar, drawn through `Figure::from`
//! — the stability figure); `crates/pendula-viz/src/heatmap.rs` holds `Heatmap` (a grid of values
//! in viridis with a colour bar ticked at round values, or discrete categories with a legend);
//! `method_style` in `crates/pendula-viz/src/lib.rs` gives each method one colour, marker and line
//! pattern everywhere, from its position in `METHODS`; `crates/pendula-viz/src/labels.rs` turns
//! catalogue names and units into symbols (`pretty`: theta1 → θ₁; `axis_label`, `with_unit`: no
//! unit printed for a dimensionless system). `crates/pendula-viz/src/animate.rs` lays each frame
//! out in bands (title, the pendulum's whole reach, the energy gauges) so that nothing overlaps,
//! draws anti-aliased frames with tiny-skia and text with plotters, and encodes GIFs with a fixed
//! palette and alternating whole-centisecond delays that give the stated frame rate (1 to 50 fps).

pub mod animate;
mod bars;
mod figure;
mod heatmap;
mod labels;
mod plot;
pub mod ticks;

pub use animate::{Animation, Layout, Snapshot, gif_delays};

pub use bars::{Bar, Bars};
pub use figure::{Dash, Figure, Kind, Legend, MARKERS, Marker, Scale, Series, Style};
pub use heatmap::Heatmap;
pub use labels::{axis_label, pretty, symbol, system_axis_label, unit, with_unit};
pub use ticks::number;

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
    /// A setting the output format cannot represent (a GIF frame rate, say).
    #[error("{0}")]
    Unsupported(String),
    /// Nothing to draw (no finite points, or a log axis with no positive values).
    #[error("nothing to draw in `{0}`: no finite points in range")]
    Empty(String),
}

/// An RGB colour.
pub type Rgb = RGBColor;

/// The colour with these red, green and blue levels.
pub const fn rgb(r: u8, g: u8, b: u8) -> Rgb {
    RGBColor(r, g, b)
}

/// Black, for cells without a value (a flip fractal's "no flip").
pub const BLACK: Rgb = RGBColor(0, 0, 0);

/// Fourteen clearly distinct hues, in the order methods are registered: the Okabe & Ito
/// (2008) colour-blind-safe set first, then Paul Tol's darker muted colours. Neighbours in
/// hue (the two greens, the blues) are far apart in lightness; colour-blind readers tell
/// methods apart by the line pattern and marker of [`method_style`] as well.
const PALETTE: [Rgb; 14] = [
    RGBColor(213, 94, 0),    // vermillion
    RGBColor(0, 114, 178),   // blue
    RGBColor(0, 158, 115),   // bluish green
    RGBColor(204, 121, 167), // reddish purple
    RGBColor(230, 159, 0),   // orange
    RGBColor(86, 180, 233),  // sky blue
    RGBColor(90, 90, 90),    // dark grey
    RGBColor(136, 34, 85),   // wine
    RGBColor(153, 153, 51),  // olive
    RGBColor(120, 94, 240),  // violet
    RGBColor(166, 86, 40),   // brown
    RGBColor(238, 51, 119),  // magenta
    RGBColor(17, 90, 40),    // dark green
    RGBColor(34, 34, 120),   // navy
];

/// Black, for exact solutions and references.
pub const REFERENCE: Rgb = RGBColor(0, 0, 0);

/// Light grey, for guide lines.
pub const GUIDE: Rgb = RGBColor(150, 150, 150);

/// The colour of a method, the same in every figure: its position in
/// [`pendula::integrator::METHODS`] picks a palette entry.
pub fn method_color(name: &str) -> Rgb {
    method_style(name).color
}

/// The style of a method, the same in every figure and distinct for every method: its
/// position i in [`pendula::integrator::METHODS`] picks the colour (palette entry i), the
/// marker (i mod 7) and the line pattern (solid for the first seven, dashed for the next
/// seven), so that (marker, pattern) alone tells the 14 methods apart in grey print.
/// A name not in the registry gets grey, crosses and a dotted line.
pub fn method_style(name: &str) -> Style {
    match pendula::integrator::METHODS.iter().position(|m| m.name == name) {
        Some(i) => Style {
            color: PALETTE[i % PALETTE.len()],
            marker: MARKERS[i % MARKERS.len()],
            dash: [Dash::Solid, Dash::Dashed, Dash::Dotted][(i / MARKERS.len()) % 3],
        },
        None => Style { color: RGBColor(120, 120, 120), marker: Marker::Cross, dash: Dash::Dotted },
    }
}

/// The i-th colour of the palette, for series that are not methods.
pub fn palette(i: usize) -> Rgb {
    PALETTE[i % PALETTE.len()]
}

/// The i-th style for series that are not methods (orbits, damping ratios): the palette
/// colour with the marker and line pattern that a method at that position would have.
pub fn series_style(i: usize) -> Style {
    Style {
        color: palette(i),
        marker: MARKERS[i % MARKERS.len()],
        dash: [Dash::Solid, Dash::Dashed, Dash::Dotted][(i / MARKERS.len()) % 3],
    }
}
