//! `Solution.animate()`: the frames drawn and encoded as a GIF by pendula's own animation code
//! (`pendula-viz`, as `pendula animate`), so a notebook shows a run without matplotlib.

use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pendula_viz::{Animation, Snapshot};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::raise;

/// A GIF of `angles` (frames × pendulums × links, rad from the downward vertical) at times
/// `t` (s) with each pendulum's relative energy error `energy_error` (frames × pendulums),
/// drawn with rods of `lengths` (m) in `width` × `height` pixels at `fps` frames a second.
#[pyfunction]
#[pyo3(signature = (title, lengths, t, angles, energy_error, labels, fps, width, height))]
#[allow(clippy::too_many_arguments)] // the animation's description, as Python passes it
pub(crate) fn animation_gif<'py>(
    py: Python<'py>,
    title: String,
    lengths: Vec<f64>,
    t: PyReadonlyArray1<'py, f64>,
    angles: PyReadonlyArray3<'py, f64>,
    energy_error: PyReadonlyArray2<'py, f64>,
    labels: Vec<String>,
    fps: u32,
    width: u32,
    height: u32,
) -> PyResult<Bound<'py, PyBytes>> {
    let (t, angles, errors) = (t.as_array(), angles.as_array(), energy_error.as_array());
    let (frames, pendulums, links) = angles.dim();
    if t.len() != frames || errors.dim() != (frames, pendulums) || lengths.len() != links {
        return Err(raise(
            py,
            "InvalidValueError",
            format!(
                "inconsistent animation: {} times, angles {:?}, energy errors {:?}, {} lengths",
                t.len(),
                angles.dim(),
                errors.dim(),
                lengths.len()
            ),
        ));
    }
    if !(64..=4096).contains(&width) || !(64..=4096).contains(&height) {
        return Err(raise(
            py,
            "InvalidValueError",
            format!("invalid size {width}x{height}: each side 64 to 4096 pixels"),
        ));
    }
    let animation = Animation {
        title,
        lengths,
        frames: (0..frames)
            .map(|k| Snapshot {
                t: t[k],
                angles: (0..pendulums).map(|p| (0..links).map(|l| angles[[k, p, l]]).collect()).collect(),
                energy_error: (0..pendulums).map(|p| errors[[k, p]].abs()).collect(),
            })
            .collect(),
        size: (width, height),
        fps,
        trail: (fps as usize * 2).max(2),
        labels,
    };
    let gif = py.detach(|| animation.gif()).map_err(|e| raise(py, "InvalidValueError", e.to_string()))?;
    Ok(PyBytes::new(py, &gif))
}
