//! Animations decode as GIFs of the requested size, frame count and duration, and the
//! pendulums never reach into the bands that hold the text and the energy gauges.

use pendula_viz::{Animation, Snapshot, gif_delays};

fn animation(frames: usize) -> Animation {
    Animation {
        title: "double pendulum".into(),
        lengths: vec![1.0, 1.0],
        frames: (0..frames)
            .map(|k| {
                let t = k as f64 / 30.0;
                Snapshot {
                    t,
                    angles: vec![vec![2.0 * t.cos(), -0.2 + t], vec![2.0 * t.cos() + 0.01, -0.2 + 1.1 * t]],
                    energy_error: vec![1e-9 * (1.0 + t), 1e-4],
                }
            })
            .collect(),
        size: (320, 240),
        fps: 30,
        trail: 20,
        labels: vec!["θ₁ = 120°".into(), "θ₁ = 120° + 10⁻³ rad".into()],
    }
}

fn decode(bytes: &[u8]) -> Vec<(u16, Vec<u8>)> {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options.read_info(std::io::Cursor::new(bytes)).unwrap();
    let mut frames = Vec::new();
    while let Some(frame) = decoder.read_next_frame().unwrap() {
        frames.push((frame.delay, frame.buffer.to_vec()));
    }
    frames
}

#[test]
fn gif_has_the_requested_size_and_frame_count() {
    let a = animation(12);
    let bytes = a.gif().unwrap();
    let decoder = gif::DecodeOptions::new().read_info(std::io::Cursor::new(&bytes)).unwrap();
    assert_eq!((decoder.width(), decoder.height()), (320, 240));
    let frames = decode(&bytes);
    assert_eq!(frames.len(), 12);
    let coloured = frames[11].1.chunks(4).filter(|p| p[0] != p[1] || p[1] != p[2]).count();
    assert!(coloured > 200, "the bobs and trails are coloured: {coloured} pixels");
}

/// GIF delays are whole centiseconds: n frames at `fps` must last 100 n / fps cs (to the
/// nearest centisecond), with no delay under 2 cs (browsers show those as 10 cs).
#[test]
fn gif_delays_give_the_stated_frame_rate() {
    for fps in [1, 2, 3, 7, 10, 12, 15, 20, 24, 25, 30, 40, 48, 50] {
        for n in [1, 2, 29, 30, 31, 100, 301] {
            let delays = gif_delays(fps, n).unwrap();
            assert_eq!(delays.len(), n);
            let total: u64 = delays.iter().map(|d| *d as u64).sum();
            let exact = 100.0 * n as f64 / fps as f64;
            assert!((total as f64 - exact).abs() <= 0.5, "{fps} fps, {n} frames: {total} cs, not {exact}");
            assert!(delays.iter().all(|d| *d >= 2), "{fps} fps: {delays:?}");
            // Every prefix is on time too: no drift within the animation.
            let mut sum = 0.0;
            for (k, d) in delays.iter().enumerate() {
                sum += *d as f64;
                assert!((sum - 100.0 * (k + 1) as f64 / fps as f64).abs() <= 0.5);
            }
        }
    }
    // 30 fps alternates 3 and 4 cs (the old fixed 3 cs played 10 % fast).
    assert_eq!(gif_delays(30, 6).unwrap(), vec![3, 4, 3, 3, 4, 3]);
    for fps in [0, 51, 60, 100] {
        let e = gif_delays(fps, 10).unwrap_err().to_string();
        assert!(e.contains(&fps.to_string()) && e.contains("1 to 50"), "{e}");
    }
}

#[test]
fn encoded_gif_lasts_as_long_as_its_frame_rate_says() {
    let mut a = animation(45);
    a.fps = 30;
    let total: u32 = decode(&a.gif().unwrap()).iter().map(|(d, _)| *d as u32).sum();
    assert_eq!(total, 150, "45 frames at 30 fps last 1.5 s");
    a.fps = 60;
    assert!(a.gif().is_err());
}

/// Anti-aliasing: the rods' edges have intermediate greys, not only black and white.
#[test]
fn frames_are_anti_aliased() {
    let rgb = animation(30).frame_rgb(29).unwrap();
    let greys = rgb.chunks(3).filter(|p| p[0] == p[1] && p[1] == p[2] && p[0] > 60 && p[0] < 200).count();
    assert!(greys > 50, "{greys} intermediate grey pixels");
    if let Ok(dir) = std::env::var("PENDULA_VIZ_DUMP") {
        let mut out = std::fs::File::create(format!("{dir}/frame.png")).unwrap();
        let mut enc = png::Encoder::new(&mut out, 320, 240);
        enc.set_color(png::ColorType::Rgb);
        enc.write_header().unwrap().write_image_data(&rgb).unwrap();
    }
}

/// Two pendulums whirling through every direction — straight up, sideways, down — with
/// unequal rods and long trails: over all frames and several frame shapes, no rod, bob or
/// trail pixel lies in the title band or the gauge band, and the gauges are drawn there.
#[test]
fn pendulums_stay_clear_of_the_text_and_the_gauges() {
    for size in [(480, 480), (640, 360), (300, 600), (200, 240)] {
        let frames: Vec<Snapshot> = (0..120)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 60.0;
                Snapshot {
                    t: k as f64 / 30.0,
                    angles: vec![vec![a, 2.0 * a], vec![std::f64::consts::PI + 0.0 * a, -a]],
                    energy_error: vec![1e-3, 0.5],
                }
            })
            .collect();
        let anim = Animation {
            title: "reach".into(),
            lengths: vec![1.0, 1.5],
            frames,
            size,
            fps: 30,
            trail: 60,
            labels: vec!["a".into(), "b".into()],
        };
        let layout = anim.layout().unwrap();
        let (w, h) = size;
        assert!(layout.drawing_top < layout.gauge_top && layout.gauge_top < h);
        let mut reached_top = usize::MAX;
        let mut reached_bottom = 0;
        for k in 0..anim.frames.len() {
            let rgb = anim.pendulums_rgb(k).unwrap();
            for (i, p) in rgb.chunks(3).enumerate() {
                if p != [255, 255, 255] {
                    let y = i / w as usize;
                    reached_top = reached_top.min(y);
                    reached_bottom = reached_bottom.max(y);
                    assert!(
                        y >= layout.drawing_top as usize && y < layout.gauge_top as usize,
                        "{w}x{h}, frame {k}: pendulum pixel at row {y}, outside rows {}..{}",
                        layout.drawing_top,
                        layout.gauge_top
                    );
                }
            }
        }
        // The drawing uses its room (the band, or the width if narrower): straight up and
        // straight down come near its edges.
        let band = ((layout.gauge_top - layout.drawing_top) as usize).min(w as usize);
        assert!(reached_bottom - reached_top > band * 3 / 4, "{w}x{h}: {reached_top}..{reached_bottom}");
        let full = anim.frame_rgb(0).unwrap();
        let gauge_pixels = full[(layout.gauge_top * w * 3) as usize..]
            .chunks(3)
            .filter(|p| p[0] != p[1] || p[1] != p[2])
            .count();
        assert!(gauge_pixels > 100, "{w}x{h}: the coloured gauges are in their band ({gauge_pixels} pixels)");
    }
}

#[test]
fn too_small_a_frame_is_an_error_naming_a_size_that_fits() {
    let mut a = animation(3);
    a.size = (100, 100);
    let e = a.layout().unwrap_err().to_string();
    assert!(e.contains("100x100") && e.contains("at least"), "{e}");
    assert!(a.gif().is_err());
}
