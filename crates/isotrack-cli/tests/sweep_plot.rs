//! Sweep figures (`isotrack plot SWEEP_DIR`, issue 30/32 reviews att30n-7, -8 and -15): x tick
//! labels that can be read and a legend that stays inside the image, read from the SVG's text.
mod common;
use common::{bundled, isotrack, stderr, sweep_file, write};
use std::path::Path;

/// The `<text>` elements of an SVG: (x, y, text-anchor, font size px, content).
fn texts(svg: &str) -> Vec<(f64, f64, String, f64, String)> {
    let attr = |tag: &str, name: &str| -> Option<String> {
        let at = tag.find(&format!(" {name}=\""))? + name.len() + 3;
        Some(tag[at..at + tag[at..].find('"')?].to_string())
    };
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let (tag, rest) = t.split_once('>')?;
            let content = rest.split("</text>").next()?.trim().to_string();
            Some((
                attr(tag, "x")?.parse().ok()?,
                attr(tag, "y")?.parse().ok()?,
                attr(tag, "text-anchor").unwrap_or_default(),
                attr(tag, "font-size")?.parse().ok()?,
                content,
            ))
        })
        .collect()
}

/// The SVG's width, px.
fn width(svg: &str) -> f64 {
    let at = svg.find("width=\"").unwrap() + 7;
    svg[at..at + svg[at..].find('"').unwrap()].parse().unwrap()
}

/// The x axis's tick labels (centred numbers on the lowest row of such), left to right:
/// (x, font size, text).
fn x_ticks(svg: &str) -> Vec<(f64, f64, String)> {
    let numeric: Vec<_> = texts(svg)
        .into_iter()
        .filter(|t| t.2 == "middle" && t.4.parse::<f64>().is_ok())
        .collect();
    let row = numeric.iter().map(|t| t.1).fold(f64::MIN, f64::max);
    let mut ticks: Vec<_> = numeric
        .into_iter()
        .filter(|t| t.1 == row)
        .map(|t| (t.0, t.3, t.4))
        .collect();
    ticks.sort_by(|a, b| a.0.total_cmp(&b.0));
    ticks
}

/// Runs sweep `body` over the bundled circular field into `dir/o` and plots it as SVG with
/// `plot_args`; the figure's text.
fn swept_svg(dir: &Path, body: &str, plot_args: &[&str]) -> String {
    swept_svg_on(dir, &bundled("paper-fig2b-circular"), body, plot_args)
}

/// [`swept_svg`] with base scenario `scenario`.
fn swept_svg_on(dir: &Path, scenario: &str, body: &str, plot_args: &[&str]) -> String {
    let sw = sweep_file(dir, "s.toml", scenario, body);
    let (o, p) = (dir.join("o"), dir.join("p"));
    let r = isotrack(&["sweep", &sw, "--out", o.to_str().unwrap()]);
    assert!(r.status.success(), "{}", stderr(&r));
    let mut args = vec!["plot", o.to_str().unwrap()];
    args.extend_from_slice(plot_args);
    args.extend(["--format", "svg", "--out", p.to_str().unwrap()]);
    let r = isotrack(&args);
    assert!(r.status.success(), "{}", stderr(&r));
    let f = std::fs::read_dir(&p)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|f| f.extension().is_some_and(|e| e == "svg"))
        .unwrap();
    std::fs::read_to_string(f).unwrap()
}

/// att30n-7: a sweep whose x key has one whole value (`sim.seed = [5]`) was labelled
/// 4.9999999975 to 5.000000002, ten labels run together over an axis 1e-8 wide: it has one
/// label, "5".
#[test]
fn one_whole_x_value_gets_one_label() {
    let d = tempfile::tempdir().unwrap();
    let svg = swept_svg(
        d.path(),
        "[base]\nsim.duration_s = 2.0\n[grid]\nsim.seed = [5]\ncontroller.kp = [5.0, 10.0]\n",
        &[
            "--x",
            "sim.seed",
            "--metric",
            "path_length_m",
            "--group",
            "controller.kp",
        ],
    );
    let ticks: Vec<String> = x_ticks(&svg).into_iter().map(|t| t.2).collect();
    assert_eq!(ticks, ["5"], "{svg}");
}

/// att38-7: one x value that is not whole (`controller.kp = [5.5]`) was labelled
/// 5.499999997 to 5.500000003, the last label cut at the image's edge; a metric the same in
/// every run (`t_end_s`, 2 s) got nine y labels 1e-9 apart over the axis title. Each now has
/// one label, the value as written, inside the image.
#[test]
fn one_value_that_is_not_whole_gets_one_label() {
    let d = tempfile::tempdir().unwrap();
    let svg = swept_svg(
        d.path(),
        "[base]\nsim.duration_s = 2.0\n[grid]\ncontroller.kp = [5.5]\ncontroller.ki = [0.0, 1.0]\n",
        &["--x", "controller.kp", "--metric", "t_end_s"],
    );
    let ticks: Vec<String> = x_ticks(&svg).into_iter().map(|t| t.2).collect();
    assert_eq!(ticks, ["5.5"], "{svg}");
    let y: Vec<(f64, String)> = texts(&svg)
        .into_iter()
        .filter(|t| t.2 == "end" && t.4.parse::<f64>().is_ok())
        .map(|t| (t.0, t.4))
        .collect();
    assert_eq!(y.len(), 1, "{y:?}");
    assert_eq!(y[0].1, "2");
    assert!(y[0].0 > 0.0 && y[0].0 < width(&svg), "{y:?}");
}

/// att30n-15: twelve consecutive seeds near 1e9 got a label each, 13 characters wide 37 px
/// apart: they ran together. Neighbouring labels are now at least their half-widths apart
/// (a DejaVu Sans digit is 0.636 em: 0.64 em a character bounds them) and at least two are
/// drawn, on whole numbers a whole step apart.
#[test]
fn wide_whole_number_labels_are_thinned_until_they_do_not_overlap() {
    let d = tempfile::tempdir().unwrap();
    let seeds: Vec<String> = (0..12)
        .map(|i| (1_000_000_000u64 + i).to_string())
        .collect();
    let svg = swept_svg(
        d.path(),
        &format!(
            "[base]\nsim.duration_s = 2.0\nsensor.noise_std = 0.1\n[grid]\nsim.seed = [{}]\n",
            seeds.join(", ")
        ),
        &["--x", "sim.seed", "--metric", "steady_state_rms_error"],
    );
    let ticks = x_ticks(&svg);
    assert!(ticks.len() >= 2, "{ticks:?}");
    let w = |t: &(f64, f64, String)| 0.64 * t.1 * t.2.chars().count() as f64;
    for p in ticks.windows(2) {
        assert!(
            p[1].0 - p[0].0 >= 0.5 * (w(&p[0]) + w(&p[1])),
            "overlap: {ticks:?}"
        );
        let (a, b): (f64, f64) = (p[0].2.parse().unwrap(), p[1].2.parse().unwrap());
        assert!(b - a >= 1.0 && (b - a).fract() == 0.0, "{ticks:?}");
    }
}

/// att30n-8: group labels holding long absolute paths made a legend wider than the image: both
/// labels cut at its right edge ("first_variant_of_the_map_", "second_variant_of_the_m"),
/// indistinguishable. Each label now ends inside the image (0.6 em a character, the legend's
/// own estimate) and shows its file's name from its start, where the two differ.
#[test]
fn long_group_labels_stay_inside_the_image_and_apart() {
    let d = tempfile::tempdir().unwrap();
    let long = d.path().join("longdir").join("a".repeat(60));
    std::fs::create_dir_all(&long).unwrap();
    let names = [
        "first_variant_of_the_map_with_a_long_name.csv",
        "second_variant_of_the_map_with_a_long_name.csv",
    ];
    // `20 exp(-0.1 r)` on 81 x 81 nodes 0.5 m apart round the origin, in both files.
    let mut csv = String::new();
    for j in 0..81 {
        let row: Vec<String> = (0..81)
            .map(|i| {
                let (x, y) = (0.5 * (i as f64 - 40.0), 0.5 * (j as f64 - 40.0));
                format!("{}", 20.0 * (-0.1 * (x * x + y * y).sqrt()).exp())
            })
            .collect();
        csv.push_str(&row.join(","));
        csv.push('\n');
    }
    for n in names {
        std::fs::write(long.join(n), &csv).unwrap();
    }
    let scenario = write(
        d.path(),
        "grid.toml",
        "[field]\nkind = \"grid\"\npath = \"x.csv\"\nspacing_m = [0.5, 0.5]\norigin_m = [-20.0, -20.0]\n[initial]\nx_m = 5.0\ny_m = 0.0\n",
    );
    std::fs::write(d.path().join("x.csv"), &csv).unwrap();
    let paths: Vec<String> = names
        .iter()
        .map(|n| format!("{:?}", long.join(n).display().to_string()))
        .collect();
    let svg = swept_svg_on(
        d.path(),
        &scenario,
        &format!(
            "[base]\nsim.duration_s = 2.0\n[grid]\nfield.path = [{}]\ncontroller.kp = [1.0, 5.0, 10.0]\n",
            paths.join(", ")
        ),
        &[
            "--x",
            "controller.kp",
            "--metric",
            "steady_state_rms_error",
            "--group",
            "field.path",
        ],
    );
    let w = width(&svg);
    let legend: Vec<_> = texts(&svg)
        .into_iter()
        .filter(|t| t.4.starts_with("field.path = "))
        .collect();
    assert_eq!(legend.len(), 2, "{svg}");
    for (t, name) in legend.iter().zip(names) {
        let end = t.0 + 0.6 * t.3 * t.4.chars().count() as f64;
        assert!(t.0 >= 0.0 && end <= w, "{t:?} in {w} px");
        // The file name from its start (where the two differ), after the folder's `…/`.
        let start = &name[..name.find('_').unwrap()];
        assert!(t.4.contains(&format!("\u{2026}/{start}_variant")), "{t:?}");
    }
    assert_ne!(legend[0].4, legend[1].4);
}

/// att36-22: an integer x column (`sim.seed`) was grouped through `f64`, so seeds above 2^53
/// one apart (2^53 and 2^53 + 1 are one `f64`) merged into one "mean ± std" point, and the
/// labels ran together. Each seed is its own point (one run each, its own metric), and the x
/// labels are the seeds exactly.
#[test]
fn seeds_beyond_two_to_the_53_are_distinct_points_labelled_exactly() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().join("seeds");
    std::fs::create_dir_all(&dir).unwrap();
    let seeds = [
        "9007199254740992",
        "9007199254740993",
        "9007199254740994",
        "9007199254740995",
    ];
    let mut csv = "run_id,sim.seed,outcome,steady_state_max_abs_error\n".to_string();
    for (i, s) in seeds.iter().enumerate() {
        csv.push_str(&format!("{i},{s},completed,{}\n", 2 * (i + 1)));
    }
    write(&dir, "results.csv", &csv);
    let (lines, skipped) = isotrack_plot::sweep_summary(
        &dir.join("results.csv"),
        "sim.seed",
        "steady_state_max_abs_error",
        None,
    )
    .unwrap();
    assert_eq!(skipped, 0);
    let pts = &lines[0].1;
    // One run per seed: four points, each its seed's metric, no spread.
    let got: Vec<(f64, f64, usize)> = pts.iter().map(|p| (p.1, p.2, p.3)).collect();
    assert_eq!(
        got,
        [(2.0, 0.0, 1), (4.0, 0.0, 1), (6.0, 0.0, 1), (8.0, 0.0, 1)]
    );
    let o = isotrack(&[
        "plot",
        dir.to_str().unwrap(),
        "--x",
        "sim.seed",
        "--format",
        "svg",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let svg = std::fs::read_to_string(dir.join("sweep_steady_state_max_abs_error_vs_sim_seed.svg"))
        .unwrap();
    let labels: Vec<String> = common::svg_texts(&svg).into_iter().map(|t| t.3).collect();
    // The x labels (as many as fit side by side) are seeds, written whole.
    let x_labels: Vec<&String> = labels.iter().filter(|l| l.starts_with("900719")).collect();
    assert!(x_labels.len() >= 2, "{labels:?}");
    for l in x_labels {
        assert!(seeds.contains(&l.as_str()), "{l} is no seed: {labels:?}");
    }
}

/// att49-3: a genuine sweep at `controller.kp = 1e300` (its chattering reaches about 1e301
/// rad/s^2) was refused 65, "beyond the +-1e100 a plot can show", for the x axis and the
/// metric, though `plot RUN_DIR` draws the same run clipped. Both axes are drawn at the bound
/// now, each label saying so, as a run's time series; the axis within the bound has no note.
#[test]
fn a_sweep_past_the_axis_bound_is_drawn_clipped() {
    let d = tempfile::tempdir().unwrap();
    let svg = swept_svg(
        d.path(),
        "[base]\nsim.duration_s = 20.0\n[grid]\ncontroller.kp = [5.0, 1e300]\n",
        &["--x", "controller.kp", "--metric", "chattering_radps2"],
    );
    assert!(svg.contains("controller.kp (clipped at"), "{svg}");
    assert!(svg.contains("chattering_radps2 (clipped at"), "{svg}");
    let d = tempfile::tempdir().unwrap();
    let svg = swept_svg(
        d.path(),
        "[base]\nsim.duration_s = 20.0\n[grid]\ncontroller.kp = [5.0, 1e300]\n",
        &["--x", "controller.kp", "--metric", "path_length_m"],
    );
    assert!(svg.contains("controller.kp (clipped at"), "{svg}");
    assert!(!svg.contains("path_length_m (clipped"), "{svg}");
}
