//! The study commands end to end: their headline numbers, their files (CSV columns, PNG and
//! GIF that decode to the right size), and their errors.

use std::path::Path;

use tempfile::TempDir;

use crate::util::{json, pendula, svg_texts};

fn header(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap().lines().next().unwrap().to_owned()
}

/// A chart is 600 pixels high and 960 wide, plus the legend's column when the legend goes
/// outside the plot.
macro_rules! assert_chart_size {
    ($size:expr) => {
        assert_chart_size!($size, "chart")
    };
    ($size:expr, $($msg:tt)+) => {{
        let (w, h): (u32, u32) = $size;
        assert!(h == 600 && (960..1400).contains(&w), "{}: {w}x{h}", format!($($msg)+));
    }};
}

fn png_size(path: &Path) -> (u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let reader = decoder.read_info().unwrap();
    let info = reader.info();
    (info.width, info.height)
}

#[test]
fn ref_convergence_orders_of_the_oscillator() {
    let dir = TempDir::new().unwrap();
    pendula(dir.path(), &["convergence", "oscillator", "--out-dir", "c", "--summary", "s.json"]).success();
    let s = json(&dir.path().join("s.json"));
    let orders = s["tables"]["orders"].as_array().unwrap();
    for (method, order) in [("euler", 1.0), ("rk4", 4.0), ("symplectic-euler", 1.0), ("verlet", 2.0)] {
        let row = orders.iter().find(|r| r["method"] == method).unwrap();
        let fitted = row["fitted_order"].as_f64().unwrap();
        assert!((fitted - order).abs() <= 0.1, "{method}: {fitted}");
    }
    assert_eq!(s["reference"], "exact solution");
    assert_eq!(header(&dir.path().join("c/convergence.csv")), "method,dt,error");
    assert_chart_size!(png_size(&dir.path().join("c/convergence.png")));
    assert!(std::fs::read_to_string(dir.path().join("c/convergence.svg")).unwrap().starts_with("<svg"));
}

#[test]
fn ref_period_at_170_degrees_matches_the_exact_period() {
    let dir = TempDir::new().unwrap();
    pendula(dir.path(), &["period", "--out-dir", "p", "--summary", "s.json"]).success();
    let s = json(&dir.path().join("s.json"));
    let row = s["tables"]["period"].as_array().unwrap().iter().find(|r| r["amplitude_deg"] == 170.0).unwrap();
    let (sim, exact) = (row["simulated"].as_f64().unwrap(), row["exact"].as_f64().unwrap());
    assert!((sim / exact - 1.0).abs() < 1e-6, "{sim} vs {exact}");
    assert!((exact - 4.893_524_274_105_486).abs() < 1e-12, "mpmath's 4 sqrt(l/g) K(sin 85°)");
    assert!(row["small_angle"].as_f64().unwrap() < 0.5 * exact);
    assert_eq!(header(&dir.path().join("p/period.csv")), "amplitude_deg,simulated,exact,small_angle");
    assert_chart_size!(png_size(&dir.path().join("p/period.png")));
}

#[test]
fn compare_writes_its_summary_and_figures() {
    let dir = TempDir::new().unwrap();
    let out =
        pendula(dir.path(), &["compare", "pendulum", "--dt", "0.05", "--t-end", "200", "--out-dir", "c"])
            .success();
    let table = String::from_utf8(out.get_output().stdout.clone()).unwrap();
    assert!(table.contains("verlet") && table.contains("max rel. error"), "{table}");
    assert!(table.contains("relative to the energy scale 9.81"), "m g l for the pendulum: {table}");
    assert_eq!(
        header(&dir.path().join("c/summary.csv")),
        "method,dt,steps,rhs_evals,cost_evals,wall_s,max_rel_energy_error,max_abs_energy_error,drift_rate,growth,failure"
    );
    let csv = std::fs::read_to_string(dir.path().join("c/summary.csv")).unwrap();
    let field = |method: &str, k: usize| -> String {
        let line = csv.lines().find(|l| l.starts_with(&format!("{method},"))).unwrap();
        line.split(',').nth(k).unwrap().to_owned()
    };
    let error = |method: &str| -> f64 { field(method, 6).parse().unwrap() };
    // Euler's energy runs away; Verlet's stays bounded and small at this step.
    assert!(error("euler") > 100.0 * error("verlet"), "{csv}");
    assert_eq!(field("verlet", 9), "bounded");
    assert_eq!(field("euler", 9), "growing");
    for name in ["trajectory", "phase_euler", "phase_rk4", "phase_symplectic-euler", "phase_verlet"] {
        assert_chart_size!(png_size(&dir.path().join(format!("c/{name}.png"))), "{name}");
    }
    // The energy figure: the chart, and below it a panel over the span of Euler's run, which
    // was stopped when its error reached the energy scale.
    let (w, h) = png_size(&dir.path().join("c/energy.png"));
    assert!(h == 1200 && (960..1400).contains(&w), "energy: {w}x{h}");
    let svg = std::fs::read_to_string(dir.path().join("c/energy.svg")).unwrap();
    assert!(svg.contains("euler over its own run") && svg.contains("euler (stopped at t = "), "energy.svg");
}

#[test]
fn compare_at_equal_cost_spends_the_same_evaluations_and_times_the_crossover() {
    let dir = TempDir::new().unwrap();
    let out = pendula(
        dir.path(),
        &[
            "compare",
            "pendulum",
            "--set",
            "theta=150deg",
            "--methods",
            "rk4,verlet,symplectic-euler",
            "--evals-per-second",
            "40",
            "--t-end",
            "3000",
            "--out-dir",
            "c",
            "--summary",
            "s.json",
        ],
    )
    .success();
    let s = json(&dir.path().join("s.json"));
    let m = &s["methods"];
    let cost = |name: &str| m[name]["cost_evals"].as_f64().unwrap();
    for name in ["verlet", "symplectic-euler"] {
        let ratio = cost(name) / cost("rk4");
        assert!((ratio - 1.0).abs() < 0.05, "{name} spent {ratio} of rk4's evaluations");
        assert_eq!(m[name]["growth"], "bounded", "{name}");
    }
    assert_eq!(m["rk4"]["growth"], "growing");
    // The sentence printed matches the crossover recorded beside the numbers.
    let stdout = String::from_utf8(out.get_output().stdout.clone()).unwrap();
    for c in s["crossovers"].as_array().unwrap() {
        let bounded = c["bounded"].as_str().unwrap();
        let bound = c["bound"].as_f64().unwrap();
        assert!((bound - m[bounded]["max_rel_energy_error"].as_f64().unwrap()).abs() <= 1e-12 * bound);
        let line = stdout.lines().find(|l| l.starts_with("crossover:") && l.contains(bounded)).unwrap();
        assert_eq!(line.contains("passes"), c["t"].is_number(), "{line}");
        // A crossover beyond the run is printed as an extrapolation, from the drift recorded.
        assert_eq!(line.contains("(extrapolated)"), c["t_extrapolated"].is_number(), "{line}");
        if let Some(t) = c["t_extrapolated"].as_f64() {
            let rate = m["rk4"]["drift_rate"].as_f64().unwrap();
            assert!((t - bound / rate.abs()).abs() <= 1e-9 * t, "{t} from {bound} and {rate}");
            assert!(t > s["t_end"].as_f64().unwrap());
        }
    }
    // The trajectory figure draws each method's first seconds as a curve, not the one
    // sample of a 3000 s run's thinned record that falls in them.
    let svg = std::fs::read_to_string(dir.path().join("c/trajectory.svg")).unwrap();
    let curves = svg
        .split("<polyline")
        .skip(1)
        .filter(|p| p.split("points=\"").nth(1).is_some_and(|pts| pts.split(' ').count() > 100))
        .count();
    assert!(curves >= 3, "{curves} curves in the trajectory figure");
}

#[test]
fn stability_and_regimes_write_their_tables() {
    let dir = TempDir::new().unwrap();
    pendula(dir.path(), &["stability", "--methods", "euler,verlet", "--out-dir", "s", "--summary", "s.json"])
        .success();
    let s = json(&dir.path().join("s.json"));
    let step = |m: &str| {
        let rows = s["tables"]["stability"].as_array().unwrap();
        rows.iter().find(|r| r["method"] == m).unwrap()["largest_stable_dt"].as_f64().unwrap()
    };
    let (euler, verlet) = (step("euler"), step("verlet"));
    assert!(euler < verlet / 10.0, "euler {euler}, verlet {verlet}");
    assert_eq!(header(&dir.path().join("s/stability.csv")), "method,largest_stable_dt,note");
    pendula(dir.path(), &["oscillator-regimes", "--out-dir", "r", "--summary", "r.json"]).success();
    let r = json(&dir.path().join("r.json"));
    assert!(r["max_rel_amplitude_error"].as_f64().unwrap() < 1e-6);
    assert_eq!(
        header(&dir.path().join("r/resonance.csv")),
        "zeta,drive_ratio,amplitude_exact,amplitude_simulated,phase_exact,phase_simulated"
    );
    for name in ["regimes", "resonance_amplitude", "resonance_phase"] {
        assert_chart_size!(png_size(&dir.path().join(format!("r/{name}.png"))));
    }
}

#[test]
fn animate_writes_a_gif_with_one_frame_per_sample() {
    let dir = TempDir::new().unwrap();
    pendula(
        dir.path(),
        &[
            "animate",
            "double",
            "--t-end",
            "1",
            "--fps",
            "10",
            "--size",
            "240x200",
            "--compare",
            "1e-3",
            "--out",
            "a.gif",
        ],
    )
    .success();
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options.read_info(std::fs::File::open(dir.path().join("a.gif")).unwrap()).unwrap();
    assert_eq!((decoder.width(), decoder.height()), (240, 200));
    let mut frames = 0;
    while decoder.read_next_frame().unwrap().is_some() {
        frames += 1;
    }
    // t = 0, 0.1, ..., 1.0 s.
    assert_eq!(frames, 11);
}

/// A table's header and rows.
type Table = (Vec<String>, Vec<Vec<String>>);

/// The tables captioned "Data of Figure N" in a report: N, the header and the rows.
fn figure_tables(html: &str) -> Vec<(usize, Table)> {
    let unescape =
        |s: &str| s.replace("&lt;", "<").replace("&gt;", ">").replace("&quot;", "\"").replace("&amp;", "&");
    html.split("<caption>Data of Figure ")
        .skip(1)
        .map(|t| {
            let (n, rest) = t.split_once("</caption>").unwrap();
            let table = rest.split("</table>").next().unwrap();
            let mut rows = table.split("<tr>").skip(1);
            let header = rows
                .next()
                .unwrap()
                .split("<th>")
                .skip(1)
                .map(|c| unescape(c.split("</th>").next().unwrap()))
                .collect();
            let rows = rows
                .map(|r| {
                    r.split("<td>").skip(1).map(|c| unescape(c.split("</td>").next().unwrap())).collect()
                })
                .collect();
            (n.parse().unwrap(), (header, rows))
        })
        .collect()
}

#[test]
fn report_is_one_self_contained_page() {
    let dir = TempDir::new().unwrap();
    pendula(dir.path(), &["report", "--out-dir", "r"]).success();
    let html = std::fs::read_to_string(dir.path().join("r/report.html")).unwrap();
    assert!(html.matches("src=\"data:image/png;base64,").count() >= 18);
    assert!(html.contains("src=\"data:image/gif;base64,"));
    assert!(!html.contains("src=\"http") && !html.contains("src=\"/"), "no external images");
    for section in [
        "§2",
        "§7.3",
        "§8",
        "ERRATA",
        "Contents",
        "Lyapunov",
        "Poincaré",
        "flip fractal",
        "Bifurcation",
        "work-precision",
    ] {
        assert!(html.contains(section), "{section}");
    }
    // Numbered sections, without repeats, each in the table of contents.
    let headings: Vec<&str> =
        html.split("<h2 id=\"s").skip(1).map(|h| h.split("</h2>").next().unwrap()).collect();
    assert!(headings.len() >= 12, "{headings:?}");
    for (k, h) in headings.iter().enumerate() {
        assert!(h.starts_with(&format!("{}\">{}. ", k + 1, k + 1)), "section {}: {h}", k + 1);
        assert!(html.contains(&format!("<a href=\"#s{}\">", k + 1)), "section {} not in the contents", k + 1);
    }
    // Captions: unique, numbered in order, each naming the command that made its figure.
    let captions: Vec<&str> =
        html.split("<figcaption>").skip(1).map(|c| c.split("</figcaption>").next().unwrap()).collect();
    assert!(captions.len() >= 19);
    for (k, c) in captions.iter().enumerate() {
        assert!(c.starts_with(&format!("Figure {}. ", k + 1)), "{c}");
        assert!(c.contains("Made by <code>pendula "), "caption names no command: {c}");
        let text = c.split_once(". ").unwrap().1;
        assert_eq!(
            captions.iter().filter(|o| o.split_once(". ").unwrap().1 == text).count(),
            1,
            "repeated: {c}"
        );
    }
    // Each figure has its own table, captioned with its number, right under it (all but the
    // GIF, whose numbers are the divergence's).
    let tables = figure_tables(&html);
    assert_eq!(tables.len(), captions.len() - 1, "all but the GIF");
    for (i, (n, (header, rows))) in tables.iter().enumerate() {
        assert!(!rows.is_empty(), "Figure {n}: an empty table");
        for row in rows {
            assert_eq!(row.len(), header.len(), "Figure {n}: {row:?}");
            for c in row {
                // Integers as integers: no 30.0000, 2.0000 (a whole number through the
                // four-decimal format of reals).
                let whole = c.split_once('.').is_some_and(|(a, b)| {
                    !a.is_empty()
                        && a.trim_start_matches('-').chars().all(|d| d.is_ascii_digit())
                        && b == "0000"
                });
                assert!(!whole, "Figure {n}: {c} is a whole number printed as a float");
            }
        }
        for (m, other) in &tables[i + 1..] {
            assert!(other != &tables[i].1, "Figures {n} and {m} share a table");
        }
    }
    let table =
        |n: usize| &tables.iter().find(|t| t.0 == n).unwrap_or_else(|| panic!("Figure {n}: no table")).1;
    let column = |n: usize, name: &str| -> Vec<String> {
        let (header, rows) = table(n);
        let k = header
            .iter()
            .position(|h| h.contains(name))
            .unwrap_or_else(|| panic!("Figure {n}: {name} in {header:?}"));
        rows.iter().map(|r| r[k].clone()).collect()
    };
    let value = |n: usize, quantity: &str| -> String {
        let (_, rows) = table(n);
        rows.iter().find(|r| r[0].contains(quantity)).unwrap_or_else(|| panic!("Figure {n}: {quantity}"))[1]
            .clone()
    };
    // Figure 1 (the free decay) lists its regimes' errors in metres, not the resonance's.
    assert_eq!(column(1, "regime"), ["underdamped", "critically damped", "overdamped"]);
    assert!(
        table(1).0.iter().any(|h| h.contains("(m)")) && !table(1).0.iter().any(|h| h.contains("amplitude"))
    );
    assert!(table(2).0.iter().any(|h| h.contains("amplitude")));
    assert!(table(3).0.iter().any(|h| h.contains("lag")));
    // Figures 8–10 (work-precision, stability) hold each method's numbers.
    let wp = column(8, "evaluations to error");
    assert!(wp.len() >= 10 && wp.iter().filter(|c| c.parse::<u64>().is_ok()).count() >= 8, "{wp:?}");
    for n in [9, 10] {
        let methods = column(n, "method");
        let steps = column(n, "largest stable step h (s)");
        assert!(methods.contains(&"rk4".to_owned()) && methods.contains(&"tao-2".to_owned()), "{methods:?}");
        assert!(steps.iter().all(|h| h.parse::<f64>().is_ok_and(|h| h > 0.0)), "Figure {n}: {steps:?}");
    }
    for (n, quantity) in [
        (16, "orbits"),
        (16, "crossings"),
        (17, "threads"),
        (17, "pixels"),
        (19, "threads"),
        (19, "values of g"),
    ] {
        let v = value(n, quantity);
        assert!(v.parse::<u64>().is_ok(), "Figure {n}: {quantity} = {v}");
    }
    // Every section's prose quotes a number; the cost and stability sections quote the
    // numbers their figures' tables show.
    let sections: Vec<&str> = html.split("<h2 id=\"s").skip(1).collect();
    for (k, section) in sections.iter().enumerate() {
        let prose: String = section.split("<figure>").next().unwrap().split("<p>").skip(1).collect();
        assert!(prose.chars().any(|c| c.is_ascii_digit()), "section {}: no number in {prose:?}", k + 1);
    }
    let cost = sections[4].split("<figure>").next().unwrap();
    let cheapest = wp.iter().filter_map(|c| c.parse::<u64>().ok()).min().unwrap();
    assert!(cost.contains(&format!("with {cheapest} evaluations")), "{cost}");
    let stability = sections[5].split("<figure>").next().unwrap();
    let smallest = column(9, "largest stable step h (s)")
        .iter()
        .map(|h| h.parse::<f64>().unwrap())
        .fold(f64::INFINITY, f64::min);
    let quoted = stability.split("run from ").nth(1).unwrap().split(" s (").next().unwrap();
    assert_eq!(quoted.parse::<f64>().unwrap(), smallest, "{stability}");

    // The figures: units on every axis, one symbol per quantity, one notation per axis,
    // slope guides out of the legend, refused methods drawn as refused.
    let runs = dir.path().join("r/runs");
    let divergence = svg_texts(&runs.join("divergence/divergence.svg"));
    assert!(
        divergence.iter().any(|t| t == "distance |Δy| in state space (rad and rad/s combined)"),
        "{divergence:?}"
    );
    let bifurcation = svg_texts(&runs.join("bifurcation/bifurcation.svg"));
    assert!(bifurcation.iter().any(|t| t == "drive amplitude g (dimensionless)"), "{bifurcation:?}");
    assert!(!bifurcation.iter().any(|t| t.contains("amplitude A")), "{bifurcation:?}");
    let energy = std::fs::read_dir(&runs)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.file_name().unwrap().to_string_lossy().starts_with("compare_double"))
        .unwrap();
    let energy = svg_texts(&energy.join("energy.svg"));
    // One notation on the time axis: plain numbers to the end (90000, 100000), not a 10⁵
    // after them (the error axis below 1 has only negative powers).
    let plain = energy.iter().filter(|t| t.parse::<u64>().is_ok_and(|v| v >= 100)).count();
    let powers = energy
        .iter()
        .filter(|t| t.starts_with("10") && t.chars().nth(2).is_some_and(|c| "¹²³⁴⁵⁶⁷⁸⁹".contains(c)))
        .count();
    assert!(plain > 0 && powers == 0, "{energy:?}");
    for system in ["oscillator", "double"] {
        let texts = svg_texts(&runs.join(format!("convergence_{system}/convergence.svg")));
        for p in [1, 2, 4] {
            assert_eq!(
                texts.iter().filter(|t| **t == format!("slope {p}")).count(),
                1,
                "{system}: {texts:?}"
            );
        }
        assert!(!texts.iter().any(|t| t.contains("guides")), "{system}: {texts:?}");
    }
    let stability = svg_texts(&runs.join("stability_double/stability.svg"));
    assert_eq!(
        stability.iter().filter(|t| t.starts_with("refused above 0.005 s")).count(),
        2,
        "{stability:?}"
    );
    // The energy sections' sentences agree with their tables: the methods called bounded and
    // growing are those the table's `error` column says.
    let energy_tables: Vec<&str> = html.split("<table class=\"energy\">").skip(1).collect();
    assert_eq!(energy_tables.len(), 2);
    let paragraphs: Vec<&str> = html.split("<p>").filter(|p| p.contains("Judged from each run")).collect();
    assert_eq!(paragraphs.len(), 2);
    for (table, sentence) in energy_tables.iter().zip(&paragraphs) {
        let table = table.split("</table>").next().unwrap();
        let rows: Vec<Vec<&str>> = table
            .split("<tr>")
            .skip(2)
            .map(|r| r.split("<td>").skip(1).map(|c| c.split("</td>").next().unwrap()).collect())
            .collect();
        for verdict in ["bounded", "growing"] {
            let listed: Vec<&str> = rows.iter().filter(|r| r[5] == verdict).map(|r| r[0]).collect();
            let said =
                sentence.split(&format!("{verdict} — ")).nth(1).unwrap().split([';', '.']).next().unwrap();
            let said: Vec<&str> = said.split(", ").filter(|m| *m != "none").collect();
            assert_eq!(said, listed, "{verdict}: sentence {sentence:?}");
        }
        // Each crossover sentence quotes the bounded method's largest error from the table.
        for part in sentence.split("bounded error (").skip(1) {
            let bound = part.split(')').next().unwrap();
            let before = sentence.split(&format!("bounded error ({bound})")).next().unwrap();
            let method = before.rsplit(' ').nth(1).unwrap().trim_end_matches("'s");
            let row =
                rows.iter().find(|r| r[0] == method).unwrap_or_else(|| panic!("{method} in {sentence:?}"));
            assert_eq!(row[3], bound, "{method}: {sentence:?}");
            assert_eq!(row[5], "bounded", "{method}");
        }
    }
    // The double pendulum at equal cost: the symplectic methods bounded, RK4 and Euler growing.
    let double = energy_tables[1].split("</table>").next().unwrap();
    for (method, verdict) in [
        ("euler", "growing"),
        ("rk4", "growing"),
        ("symplectic-euler", "bounded"),
        ("verlet", "bounded"),
        ("gauss-legendre-4", "bounded"),
    ] {
        assert!(double.contains(&format!("<td>{method}</td>")), "{method}");
        let row = double.split(&format!("<td>{method}</td>")).nth(1).unwrap().split("</tr>").next().unwrap();
        assert!(row.contains(&format!("<td>{verdict}</td>")), "{method}: {row}");
    }
    // The growth rates reconciled: the table's values are the summaries' (and, for the
    // windowed rates, the long run's running estimate's), and the paragraph quotes them.
    let runs = dir.path().join("r/runs");
    let slug = |c: &str| -> String {
        c.chars().map(|ch| if ch.is_ascii_alphanumeric() || ch == '-' { ch } else { '_' }).take(60).collect()
    };
    let summary = |c: &str| json(&runs.join(slug(c)).join("summary.json"));
    let (long, default, divergence, lab) = (
        summary("lyapunov --spectrum --t-end 500"),
        summary("lyapunov"),
        summary("divergence"),
        summary("divergence --dt 0.01 --delta 7e-9 --fit-from 1e-7 --saturation 0.1"),
    );
    let pm = |s: &serde_json::Value| {
        format!("{:.3} ± {:.3}", s["lambda_max"].as_f64().unwrap(), s["uncertainty"].as_f64().unwrap())
    };
    let rate = |s: &serde_json::Value| format!("{:.3}", s["growth_rate"].as_f64().unwrap());
    let window = divergence["fit_end"].as_f64().unwrap() - divergence["fit_start"].as_f64().unwrap();
    // Finite-time rates over consecutive windows of that length, from the running average.
    let csv =
        std::fs::read_to_string(runs.join(slug("lyapunov --spectrum --t-end 500")).join("lyapunov.csv"))
            .unwrap();
    let (mut start, mut sum, mut rates) = (0.0, 0.0, Vec::new());
    for line in csv.lines().skip(1) {
        let cells: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        if cells[0] - start >= window - 1e-9 {
            rates.push((cells[1] * cells[0] - sum) / (cells[0] - start));
            (start, sum) = (cells[0], cells[1] * cells[0]);
        }
    }
    let n = rates.len() as f64;
    let mean = rates.iter().sum::<f64>() / n;
    let sd = (rates.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let want = [pm(&long), pm(&default), rate(&divergence), rate(&lab), format!("{mean:.3} ± {sd:.3}")];
    assert_eq!(html.matches("<table class=\"growth-rates\">").count(), 1);
    let table =
        html.split("<table class=\"growth-rates\">").nth(1).unwrap().split("</table>").next().unwrap();
    let values: Vec<&str> = table
        .split("<tr>")
        .skip(2)
        .map(|r| r.split("<td>").last().unwrap().split("</td>").next().unwrap())
        .collect();
    assert_eq!(values, want);
    let paragraph = html.split("<p>").find(|p| p.contains("Four growth rates")).unwrap();
    for v in &want[..4] {
        assert!(paragraph.contains(&format!("{v} 1/s")), "{v} not in {paragraph}");
    }
    assert!(paragraph.contains(&format!("standard deviation {sd:.3} 1/s")), "{paragraph}");
    assert!(paragraph.contains(&format!("Quote λ₁ = {} 1/s", want[0])), "{paragraph}");
    for entry in std::fs::read_dir(dir.path().join("r/runs/stability_double")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "png") {
            // One 34-pixel row per method under the title and the axis.
            let (w, h) = png_size(&path);
            assert!(w == 960 && h >= 130 + 34 * 11, "{}: {w}x{h}", path.display());
        }
    }
}

#[test]
fn work_precision_writes_error_and_cost() {
    let dir = TempDir::new().unwrap();
    pendula(
        dir.path(),
        &[
            "work-precision",
            "pendulum",
            "--methods",
            "rk4,gauss-legendre-4,dop853",
            "--dt-max",
            "0.1",
            "--levels",
            "7",
            "--t-end",
            "10",
            "--out-dir",
            "w",
        ],
    )
    .success();
    let csv = std::fs::read_to_string(dir.path().join("w/work_precision.csv")).unwrap();
    assert_eq!(csv.lines().next().unwrap(), "method,dt,tol,error,rhs_evals,wall_s");
    let column = |method: &str, i: usize| -> Vec<f64> {
        csv.lines()
            .filter(|l| l.starts_with(&format!("{method},")))
            .map(|l| l.split(',').nth(i).unwrap().parse().unwrap())
            .collect()
    };
    let rk4: Vec<(f64, u64)> =
        column("rk4", 3).into_iter().zip(column("rk4", 4).into_iter().map(|e| e as u64)).collect();
    // dop853 sweeps its tolerance (1e-3 … 1e-12, 10 levels): the error follows it down and
    // the work grows.
    let (tols, errors, evals) = (column("dop853", 2), column("dop853", 3), column("dop853", 4));
    assert_eq!(tols.len(), 10);
    assert_eq!((tols[0], tols[9]), (1e-3, 1e-12));
    let slope = pendula::analysis::fit_order(&tols, &errors).unwrap().order;
    assert!((0.6..=1.3).contains(&slope), "error against tolerance: slope {slope}");
    assert!(evals.windows(2).all(|w| w[1] >= w[0]), "{evals:?}");
    assert_eq!(rk4.len(), 7);
    // Halving the step doubles the work (4 evaluations a step) and cuts the error ~16-fold.
    for w in rk4.windows(2) {
        assert_eq!(w[1].1, 2 * w[0].1);
        assert!(w[1].0 < w[0].0 / 10.0, "{rk4:?}");
    }
    for name in ["work_precision_evals", "work_precision_time"] {
        assert_chart_size!(png_size(&dir.path().join(format!("w/{name}.png"))));
    }
}

#[test]
fn study_commands_reject_bad_input() {
    let dir = TempDir::new().unwrap();
    for (args, needle) in [
        (&["convergence", "--levels", "1"][..], "--levels"),
        (&["convergence", "--dt-min", "0.1", "--dt-max", "0.01"][..], "dt-min"),
        (&["compare", "--methods", "euler,rk5"][..], "unknown method `rk5`"),
        (&["compare", "pendulum", "--methods", "verlet", "--set", "damping=0.1"][..], "verlet needs"),
        (&["period", "--max-amplitude", "180"][..], "--max-amplitude"),
        (&["animate", "oscillator"][..], "use pendulum or double"),
        (&["animate", "--out", "a.png"][..], ".gif"),
        (&["animate", "--size", "10x10"][..], "--size"),
        (&["stability", "--max-energy-error", "0"][..], "--max-energy-error"),
        (
            &["divergence", "--fit-from", "0.1"][..],
            "invalid --fit-from 0.1: must be finite, >= 0 and smaller",
        ),
        (&["divergence", "--fit-from", "-1"][..], "--fit-from"),
    ] {
        let out = pendula(dir.path(), args).code(2);
        let stderr = String::from_utf8_lossy(&out.get_output().stderr).into_owned();
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
    }
}

#[test]
fn mp4_without_ffmpeg_says_so() {
    let has_ffmpeg =
        std::process::Command::new("ffmpeg").arg("-version").output().is_ok_and(|o| o.status.success());
    let dir = TempDir::new().unwrap();
    let a = pendula(dir.path(), &["animate", "--t-end", "0.2", "--out", "a.mp4"]);
    if has_ffmpeg {
        a.success();
        assert!(std::fs::metadata(dir.path().join("a.mp4")).unwrap().len() > 0);
    } else {
        let out = a.code(2);
        assert!(String::from_utf8_lossy(&out.get_output().stderr).contains("ffmpeg"));
        assert!(!dir.path().join("a.mp4").exists());
    }
}

/// Small runs pinned: a change of method, expression order or output format shows here.
#[test]
fn regress_small_run_csv() {
    let dir = TempDir::new().unwrap();
    let out = pendula(dir.path(), &["simulate", "oscillator", "--dt", "0.1", "--steps", "5", "--out", "-"])
        .success();
    insta::assert_snapshot!(String::from_utf8(out.get_output().stdout.clone()).unwrap(), @r"
    t,x,v,energy
    0.0,1.0,0.0,0.5
    0.1,0.9950041666666667,-0.09983333333333333,0.49999999306423615
    0.2,0.9800665972395833,-0.19866916527777778,0.49999998612847235
    0.30000000000000004,0.9553365428639757,-0.29551996253066265,0.49999997919270855
    0.4,0.9210610977926066,-0.38941802558044014,0.4999999722569449
    0.5,0.8775827305044371,-0.4794251576239398,0.4999999653211815
    ");
    let out = pendula(
        dir.path(),
        &["simulate", "pendulum", "--method", "verlet", "--dt", "0.1", "--steps", "5", "--out", "-"],
    )
    .success();
    insta::assert_snapshot!(String::from_utf8(out.get_output().stdout.clone()).unwrap(), @r"
    t,theta,omega,energy
    0.0,1.0471975511965976,0.0,-4.905000000000001
    0.1,1.004719005140971,-0.8387730009296126,-4.909582087854115
    0.2,0.879442951010675,-1.6306338123385216,-4.925180258296197
    0.30000000000000004,0.6785922426732665,-2.3163928383933134,-4.9538266128478705
    0.4,0.4161643833320123,-2.8225657704914844,-4.989240777569198
    0.5,0.11407908857496957,-3.076687450993198,-5.013232503852725
    ");
}

/// `pendula divergence`: for the damped oscillator the separation of two solutions is itself a
/// solution, whose envelope decays as e^(−c t / 2m): the fitted rate is −c/2m = −0.1 (closed
/// form); the chaotic double pendulum's separation grows at about 1/s (the bench's SPEC gives
/// ≈ 1 s⁻¹ for its largest Lyapunov exponent from this state).
#[test]
fn ref_divergence_rates() {
    let dir = TempDir::new().unwrap();
    let run = |args: &[&str]| {
        let mut all = args.to_vec();
        all.extend_from_slice(&["--out-dir", "d", "--summary", "s.json"]);
        pendula(dir.path(), &all).success();
        json(&dir.path().join("s.json"))
    };
    let damped = run(&[
        "divergence",
        "oscillator",
        "--set",
        "c=0.2",
        "--delta",
        "1e-3",
        "--t-end",
        "60",
        "--saturation",
        "1",
    ]);
    let rate = damped["growth_rate"].as_f64().unwrap();
    assert!((rate + 0.1).abs() < 0.005, "{rate}");
    let chaotic = run(&["divergence"]);
    let rate = chaotic["growth_rate"].as_f64().unwrap();
    assert!((0.6..1.5).contains(&rate), "{rate}");
    assert_eq!(header(&dir.path().join("d/divergence.csv")), "t,distance");
    assert_chart_size!(png_size(&dir.path().join("d/divergence.png")));
    pendula(dir.path(), &["divergence", "--delta", "0"]).code(2);
    pendula(dir.path(), &["divergence", "--variable", "phi"]).code(2);
}

#[test]
fn readme_gallery_captions_name_the_manifests_commands() {
    let dir = TempDir::new().unwrap();
    let out = pendula(dir.path(), &["report", "--gallery-list"]).success();
    let manifest: Vec<(String, String)> = String::from_utf8(out.get_output().stdout.clone())
        .unwrap()
        .lines()
        .map(|l| {
            let (name, command) = l.split_once('\t').unwrap();
            (name.to_owned(), command.to_owned())
        })
        .collect();
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md")).unwrap();
    // Every picture in the README is followed by the command that made it.
    let mut shown = Vec::new();
    for part in readme.split("](docs/gallery/").skip(1) {
        let (name, rest) = part.split_once(')').unwrap();
        let command = rest.trim_start().strip_prefix('`').and_then(|r| r.split_once('`')).map(|c| c.0);
        shown.push((name.to_owned(), command.unwrap_or("").to_owned()));
    }
    assert_eq!(shown, manifest, "README gallery and `report --gallery-list` disagree");
    let gallery = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/gallery");
    for (name, _) in &manifest {
        assert!(gallery.join(name).exists(), "docs/gallery/{name} is missing");
    }
}
