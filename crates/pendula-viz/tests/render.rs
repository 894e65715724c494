//! Figures render to PNG of the requested size and to SVG, on linear and log axes.

use pendula_viz::{Figure, Kind, Scale, method_color};

fn sample() -> Figure {
    let pts = |f: fn(f64) -> f64| (1..200).map(|k| k as f64 * 0.05).map(|t| (t, f(t))).collect::<Vec<_>>();
    Figure::new("Energy error", "time t (s)", "|relative energy error|")
        .scales(Scale::Linear, Scale::Log)
        .with("euler", method_color("euler"), Kind::Line, pts(|t| 1e-3 * t))
        .with("rk4", method_color("rk4"), Kind::Dashed, pts(|t| 1e-9 * t * t))
        .with("verlet", method_color("verlet"), Kind::LineMarkers, pts(|t| 1e-6 * (1.0 + t.sin().abs())))
}

fn decode(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    (info.width, info.height, buf)
}

#[test]
fn png_has_the_requested_size_and_is_not_blank() {
    let bytes = sample().png().unwrap();
    if let Ok(dir) = std::env::var("PENDULA_VIZ_DUMP") {
        std::fs::write(format!("{dir}/sample.png"), &bytes).unwrap();
    }
    let (w, h, pixels) = decode(&bytes);
    assert_eq!((w, h), (960, 600));
    let colored = pixels.chunks(3).filter(|p| p[0] != p[1] || p[1] != p[2]).count();
    assert!(colored > 1000, "only {colored} coloured pixels");
}

#[test]
fn svg_names_the_labels() {
    let svg = sample().svg().unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("time t (s)") && svg.contains("verlet"));
}

#[test]
fn empty_log_figure_is_an_error() {
    let fig = Figure::new("t", "x", "y").scales(Scale::Log, Scale::Log).with(
        "a",
        method_color("rk4"),
        Kind::Line,
        vec![(0.0, -1.0)],
    );
    assert!(fig.png().is_err());
}

#[test]
fn methods_keep_distinct_colours() {
    let colors: Vec<_> = pendula::integrator::METHODS.iter().map(|m| method_color(m.name)).collect();
    for (i, a) in colors.iter().enumerate() {
        for b in &colors[i + 1..] {
            assert_ne!(a, b);
        }
    }
}

/// Every method has its own colour (the palette grows with the registry).
#[test]
fn method_colours_are_distinct() {
    let colours: Vec<_> = pendula::integrator::METHODS.iter().map(|m| method_color(m.name)).collect();
    for (i, a) in colours.iter().enumerate() {
        for (j, b) in colours.iter().enumerate().skip(i + 1) {
            assert_ne!(
                a,
                b,
                "{} and {}",
                pendula::integrator::METHODS[i].name,
                pendula::integrator::METHODS[j].name
            );
        }
    }
}
