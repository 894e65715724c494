//! Figures render to PNG and SVG on linear and log axes; ticks are round and every decade
//! of a log axis is labelled; legends keep off the data; methods keep distinct styles.

use pendula_viz::ticks::{label, linear_ticks, log_ticks};
use pendula_viz::{Bar, Bars, Figure, Heatmap, Kind, Legend, Scale, method_color, method_style};

fn sample() -> Figure {
    let pts = |f: fn(f64) -> f64| (1..200).map(|k| k as f64 * 0.05).map(|t| (t, f(t))).collect::<Vec<_>>();
    Figure::new("Energy error", "time t (s)", "|relative energy error|")
        .scales(Scale::Linear, Scale::Log)
        .with_style("euler", method_style("euler"), Kind::Line, pts(|t| 1e-3 * t))
        .with_style("rk4", method_style("rk4"), Kind::Dashed, pts(|t| 1e-9 * t * t))
        .with_style(
            "verlet",
            method_style("verlet"),
            Kind::LineMarkers,
            pts(|t| 1e-6 * (1.0 + t.sin().abs())),
        )
}

fn decode(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    (info.width, info.height, buf)
}

fn dump(name: &str, bytes: &[u8]) {
    if let Ok(dir) = std::env::var("PENDULA_VIZ_DUMP") {
        std::fs::write(format!("{dir}/{name}"), bytes).unwrap();
    }
}

#[test]
fn png_has_the_requested_height_and_is_not_blank() {
    let bytes = sample().png().unwrap();
    dump("sample.png", &bytes);
    let (w, h, pixels) = decode(&bytes);
    assert!(w >= 960 && h == 600, "{w}x{h}");
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

/// Every method has its own colour, and its own (marker, line pattern) pair, so that
/// methods can be told apart without colour too.
#[test]
fn method_styles_are_distinct() {
    let methods = pendula::integrator::METHODS;
    let styles: Vec<_> = methods.iter().map(|m| method_style(m.name)).collect();
    for (i, a) in styles.iter().enumerate() {
        for (j, b) in styles.iter().enumerate().skip(i + 1) {
            let (p, q) = (methods[i].name, methods[j].name);
            assert_ne!(a.color, b.color, "{p} and {q} share a colour");
            assert_ne!((a.marker, a.dash), (b.marker, b.dash), "{p} and {q} share marker and pattern");
            // Distinct hues must also be far apart: no two within 60 in RGB distance.
            let d = |x: u8, y: u8| (x as f64 - y as f64).powi(2);
            let dist = (d(a.color.0, b.color.0) + d(a.color.1, b.color.1) + d(a.color.2, b.color.2)).sqrt();
            assert!(dist > 60.0, "{p} and {q}: colours {dist:.0} apart");
        }
        assert_eq!(method_color(methods[i].name), a.color);
    }
}

/// Log axes: a label at every power of ten for spans of 2 to 12 decades; 1, 2, 5 × 10ᵏ for
/// shorter spans; several labels even inside one decade.
#[test]
fn log_axes_label_every_decade() {
    for (lo, hi) in [(1e-12, 1e-2), (3e-7, 2e-3), (0.8e-5, 2.0), (1e-3, 1.1e-1), (5e-16, 3e-4)] {
        let t = log_ticks(lo, hi);
        let (a, b) = (lo.log10().ceil() as i32, hi.log10().floor() as i32);
        for k in a..=b {
            let v = 10f64.powi(k);
            assert!(
                t.major.iter().any(|m| (m / v - 1.0).abs() < 1e-9),
                "{lo}..{hi}: no label at 1e{k}: {:?}",
                t.major
            );
        }
        assert_eq!(t.major.len(), (b - a + 1) as usize, "{lo}..{hi}: {:?}", t.major);
    }
    // 23 decades: every other one is labelled, all are ticked.
    let t = log_ticks(1e-18, 1e5);
    assert_eq!(t.major.len(), 12, "{:?}", t.major);
    assert_eq!(t.major.len() + t.minor.len(), 24);
    // 1.3 decades: 1, 2, 5 × 10ᵏ labelled.
    let t = log_ticks(0.03, 0.6);
    let want = [0.05, 0.1, 0.2, 0.5];
    assert_eq!(t.major.len(), want.len(), "{:?}", t.major);
    assert!(t.major.iter().zip(want).all(|(m, w)| (m / w - 1.0).abs() < 1e-9), "{:?}", t.major);
    // Inside one decade: at least three readable, round labels.
    let t = log_ticks(2.1, 8.3);
    assert!(t.major.len() >= 3, "{:?}", t.major);
    assert!(t.major.iter().all(|v| (v - v.round()).abs() < 1e-12), "{:?}", t.major);
}

/// "Round" means m × 10ᵏ with m in {1, 2, 5} (or an integer multiple of such a step).
fn is_round_step_multiple(v: f64, step: f64) -> bool {
    let m = step / 10f64.powf(step.log10().floor());
    [1.0, 2.0, 5.0, 10.0].iter().any(|r| (m - r).abs() < 1e-9)
        && ((v / step) - (v / step).round()).abs() < 1e-6
}

#[test]
fn ticks_are_round_numbers_with_short_labels() {
    // The fractal's colour bar spans 0.3 to 100 s: ticks at 0.5, 1, 2, 5, …, not 31.6228.
    let t = log_ticks(0.3, 100.0);
    for v in &t.major {
        let m = v / 10f64.powf(v.log10().floor());
        assert!([1.0, 2.0, 5.0].iter().any(|r| (m - r).abs() < 1e-9) || (m - 10.0).abs() < 1e-9, "{v}");
    }
    for (lo, hi) in [(0.0, 1.0), (-3.2, 3.2), (0.013, 0.0171), (-1e-6, 7e-6), (1e4, 3.3e5)] {
        let t = linear_ticks(lo, hi, 8);
        assert!(t.major.len() >= 3, "{lo}..{hi}: {:?}", t.major);
        let step = t.major[1] - t.major[0];
        for v in &t.major {
            assert!(is_round_step_multiple(*v, step), "{lo}..{hi}: {v} (step {step})");
        }
    }
    let l = |v: f64, step: f64, d: bool| label(v, step, d);
    assert_eq!(l(1e-3, 1e-3, true), "10⁻³");
    assert_eq!(l(1e5, 1e5, true), "10⁵");
    assert_eq!(l(0.05, 0.05, false), "0.05");
    assert_eq!(l(2.0, 0.5, false), "2.0");
    assert_eq!(l(-1.5, 0.5, false), "−1.5");
    assert_eq!(l(2e-6, 1e-6, false), "2×10⁻⁶");
    assert_eq!(l(30.0, 10.0, false), "30");
}

fn dense(f: impl Fn(f64) -> f64) -> Vec<(f64, f64)> {
    (0..=400).map(|k| k as f64 / 400.0).map(|x| (x, f(x))).collect()
}

/// The legend goes in a corner free of data when there is one, and outside the plot (a
/// wider canvas) when every corner holds data.
#[test]
fn the_legend_keeps_off_the_data() {
    // A line rising from the lower left to the upper right: the upper left is free.
    let rising = Figure::new("rising", "x", "y").with("a", method_color("rk4"), Kind::Line, dense(|x| x));
    let (w, _, _) = decode(&rising.png().unwrap());
    assert_eq!(w, 960, "the legend fits in a free corner");
    // Lines through all four corners: no corner is free.
    let mut crowded = Figure::new("crowded", "x", "y");
    for (i, m) in pendula::integrator::METHODS.iter().enumerate() {
        let c = i as f64 / 13.0;
        crowded = crowded.with_style(m.name, method_style(m.name), Kind::Line, dense(move |x| (x - c).abs()));
    }
    crowded = crowded.with("", method_color("rk4"), Kind::Line, dense(|x| 1.0 - x));
    let bytes = crowded.png().unwrap();
    dump("crowded.png", &bytes);
    let (w, h, _) = decode(&bytes);
    assert!(w > 960 && h == 600, "the legend goes outside: {w}x{h}");
    // An explicit corner is kept.
    let (w, _, _) = decode(&crowded.clone().legend(Legend::UpperRight).png().unwrap());
    assert_eq!(w, 960);
}

#[test]
fn bars_list_every_category_with_its_note() {
    let mut bars = Bars::new("largest stable step", "h (s)", Scale::Log);
    bars.limits = Some((1e-5, 2.0));
    for (i, m) in pendula::integrator::METHODS.iter().enumerate() {
        let value = if i == 0 { None } else { Some(1e-3 * (i as f64)) };
        let note = if i == 0 { Some("unstable at every step tried".to_owned()) } else { None };
        bars.bars.push(Bar::new(m.name, value, method_color(m.name), note));
    }
    let bytes = bars.png().unwrap();
    dump("bars.png", &bytes);
    let (_, h, _) = decode(&bytes);
    assert!(h >= 34 * 14);
    let svg = bars.svg().unwrap();
    for m in pendula::integrator::METHODS {
        assert!(svg.contains(m.name), "{} is listed", m.name);
    }
    assert!(svg.contains("unstable at every step tried"));
}

/// A categorical map uses exactly its categories' colours, with a legend, no colour bar.
#[test]
fn categorical_maps_use_discrete_colours() {
    let (yes, no) = (pendula_viz::rgb(250, 200, 30), pendula_viz::rgb(70, 20, 110));
    let map = Heatmap {
        title: "converged".into(),
        x_label: "θ₁ (rad)".into(),
        y_label: "θ₂ (rad)".into(),
        bar_label: "flip time".into(),
        x: (-3.0, 3.0),
        y: (-3.0, 3.0),
        nx: 8,
        ny: 8,
        values: (0..64).map(|k| ((k / 3) % 2) as f64).collect(),
        log: false,
        nan_color: pendula_viz::BLACK,
        categories: vec![("converged".into(), yes), ("not converged".into(), no)],
    };
    let bytes = map.png().unwrap();
    dump("categories.png", &bytes);
    let (_, _, px) = decode(&bytes);
    let count = |c: pendula_viz::Rgb| px.chunks(3).filter(|p| p == &[c.0, c.1, c.2]).count();
    assert!(count(yes) > 1000 && count(no) > 1000);
    // No viridis colour bar: its mid-range teal does not appear.
    let teal =
        px.chunks(3).filter(|p| p[0] < 60 && p[1] > 120 && p[1] < 170 && p[2] > 120 && p[2] < 150).count();
    assert_eq!(teal, 0);
}

#[test]
fn numbers_print_to_three_significant_digits() {
    use pendula_viz::number;
    for (v, s) in [
        (1e-3, "0.001"),
        (0.0123456, "0.0123"),
        (120.0, "120"),
        (-15.0, "−15"),
        (1e-9, "10⁻⁹"),
        (2.5e-9, "2.5×10⁻⁹"),
        (123456.0, "1.23×10⁵"),
        (0.5, "0.5"),
        (0.0, "0"),
    ] {
        assert_eq!(number(v), s, "{v}");
    }
}

/// Values at the ends of f64 (found by the fuzz harness's long run: plotters normalises
/// colours in f32, where they are infinite, and panicked) are drawn, in the map's colours.
#[test]
fn heat_maps_of_extreme_values_are_drawn() {
    for values in [
        vec![f64::MAX, -f64::MAX, 1.0, 0.0],
        vec![1.7e308, 1.7e308, 1.7e308, 1.7e308],
        vec![-1e300, 1e-300, 5e-324, f64::NAN],
        vec![1e-310, 2e-310, 3e-310, 4e-310],
    ] {
        for log in [false, true] {
            let map = Heatmap {
                title: "extremes".into(),
                x_label: "x".into(),
                y_label: "y".into(),
                bar_label: "v".into(),
                x: (0.0, 1.0),
                y: (0.0, 1.0),
                nx: 2,
                ny: 2,
                values: values.clone(),
                log,
                nan_color: pendula_viz::BLACK,
                categories: Vec::new(),
            };
            let bytes = map.png().unwrap_or_else(|e| panic!("{values:?} (log {log}): {e}"));
            let (w, h, _) = decode(&bytes);
            assert!(w > 0 && h > 0);
        }
    }
}

/// The texts of an SVG document, trimmed.
fn texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .map(|t| t.split_once('>').unwrap().1.split("</text>").next().unwrap().trim().to_owned())
        .collect()
}

/// One notation per axis: an axis to 100 000 reads 90000, 100000 (not 90000, 10⁵); one
/// whose ticks reach 10⁶ writes them all as m × 10ⁿ.
#[test]
fn tick_labels_of_an_axis_share_one_notation() {
    let line = |hi: f64| {
        Figure::new("t", "t (s)", "y").with("", method_color("rk4"), Kind::Line, vec![(0.0, 1.0), (hi, 2.0)])
    };
    let labels = texts(&line(1e5).svg().unwrap());
    assert!(labels.iter().any(|t| t == "90000") && labels.iter().any(|t| t == "100000"), "{labels:?}");
    assert!(!labels.iter().any(|t| t.contains('⁵')), "{labels:?}");
    let labels = texts(&line(3e6).svg().unwrap());
    assert!(labels.iter().any(|t| t == "10⁶") && labels.iter().any(|t| t == "2×10⁶"), "{labels:?}");
    assert!(!labels.iter().any(|t| t == "500000"), "{labels:?}");
}

/// A guide is named on the plot, not in the legend, and drawn thin and dashed.
#[test]
fn guides_are_named_on_the_plot_not_in_the_legend() {
    let points: Vec<(f64, f64)> = (1..=10).map(|k| (k as f64, (k * k) as f64)).collect();
    let fig = Figure::new("t", "h (s)", "error")
        .scales(Scale::Log, Scale::Log)
        .with_style("rk4", method_style("rk4"), Kind::LineMarkers, points.clone())
        .with(
            "slope 2",
            pendula_viz::GUIDE,
            Kind::Guide,
            points.iter().map(|(x, y)| (*x, y / 10.0)).collect(),
        );
    assert_eq!(fig.legend_entries(), ["rk4"]);
    let svg = fig.svg().unwrap();
    assert!(texts(&svg).iter().any(|t| t == "slope 2"), "the guide is named on the plot");
    assert_eq!(fig.series[1].dash, pendula_viz::Dash::Dashed);
    assert!(svg.contains("stroke=\"#969696\" stroke-width=\"1\""), "a thin grey line");
}

/// A refused bar is an empty hatched outline, not a filled bar like a result.
#[test]
fn refused_bars_are_hatched_not_filled() {
    let color = method_color("tao-2");
    let mut bars = Bars::new("largest stable step", "h (s)", Scale::Log);
    bars.limits = Some((1e-5, 2.0));
    bars.bars.push(Bar::new("measured", Some(0.005), color, None));
    bars.bars.push(Bar {
        refused: true,
        ..Bar::new("refused", Some(0.005), color, Some("refused above 0.005 s".into()))
    });
    let (w, h, pixels) = decode(&bars.png().unwrap());
    assert_eq!(h, 130 + 34 * 2);
    // The colour's pixels in the upper (measured) and lower (refused) half of the bars.
    let count = |rows: std::ops::Range<u32>| {
        rows.flat_map(|y| (0..w).map(move |x| ((y * w + x) * 3) as usize))
            .filter(|&i| pixels[i] == color.0 && pixels[i + 1] == color.1 && pixels[i + 2] == color.2)
            .count()
    };
    let (filled, hatched) = (count(0..h / 2), count(h / 2..h));
    assert!(filled > 2000, "{filled}");
    assert!(hatched > 100 && hatched * 3 < filled, "refused: {hatched} pixels of colour, measured: {filled}");
    assert!(texts(&bars.svg().unwrap()).iter().any(|t| t == "refused above 0.005 s"));
}
