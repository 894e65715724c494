//! Animations decode as GIFs of the requested size and frame count.

use pendula_viz::{Animation, Snapshot};

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
        labels: vec!["rk4".into(), "nearby".into()],
    }
}

#[test]
fn gif_has_the_requested_size_and_frame_count() {
    let a = animation(12);
    let bytes = a.gif().unwrap();
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options.read_info(std::io::Cursor::new(&bytes)).unwrap();
    assert_eq!((decoder.width(), decoder.height()), (320, 240));
    let mut frames = 0;
    let mut coloured = 0;
    while let Some(frame) = decoder.read_next_frame().unwrap() {
        assert_eq!((frame.width, frame.height), (320, 240));
        coloured = frame.buffer.chunks(4).filter(|p| p[0] != p[1] || p[1] != p[2]).count();
        frames += 1;
    }
    assert_eq!(frames, 12);
    assert!(coloured > 200, "the bobs and trails are coloured: {coloured} pixels");
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
