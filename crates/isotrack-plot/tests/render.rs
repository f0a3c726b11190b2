//! Figures render as valid PNG and SVG images of the expected size with non-trivial content
//! (no pixel-exact comparison).

use isotrack_plot::{
    field_map, timeseries_figure, trajectory_figure, Colormap, Format, Panels, RunData, Style,
};
use isotrack_scenario::parse_scenario;
use std::path::Path;

fn make_run(dir: &Path, sets: &[&str]) -> RunData {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let s = parse_scenario("", "<test>", &sets).unwrap();
    // Written by the one run-directory writer, as `isotrack run --out` writes it.
    let out = isotrack_runs::rundir::RunDir::open(dir, &[], &[], None).unwrap();
    let mut trace = out.trace(s.is_flying()).unwrap();
    let r = s.run(trace.writer());
    let summary = isotrack_runs::summary::Summary::of_run(&s, None, &r, &[]);
    out.finish(trace, &isotrack_runs::summary::scenario_toml(&s), &summary)
        .unwrap();
    RunData::load(dir).unwrap()
}

fn check_png(path: &Path, w: u32, h: u32) {
    let img = image::open(path).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (w, h), "{}", path.display());
    let mut colours = std::collections::HashSet::new();
    for p in img.pixels() {
        colours.insert(p.0);
    }
    assert!(
        colours.len() > 50,
        "{}: only {} colours",
        path.display(),
        colours.len()
    );
}

fn check_svg(path: &Path, w: u32, needles: &[&str]) {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.contains("<svg"), "{}", path.display());
    assert!(
        text.contains(&format!("width=\"{w}\"")),
        "{}",
        path.display()
    );
    let elements = [
        "<rect",
        "<polyline",
        "<path",
        "<line",
        "<circle",
        "<polygon",
    ]
    .iter()
    .map(|t| text.matches(t).count())
    .sum::<usize>();
    assert!(elements > 50, "{}: {elements} elements", path.display());
    for n in needles {
        assert!(text.contains(n), "{}: no `{n}`", path.display());
    }
}

#[test]
fn trajectory_timeseries_and_map_render_in_png_and_svg() {
    let dir = tempfile::tempdir().unwrap();
    let a = make_run(&dir.path().join("a"), &["sim.duration_s=60"]);
    let b = make_run(
        &dir.path().join("b"),
        &["sim.duration_s=60", "initial.x_m=-9", "initial.y_m=3"],
    );
    for f in [Format::Png, Format::Svg] {
        let st = Style::new(f);
        let traj = dir.path().join(format!("trajectory.{}", f.extension()));
        trajectory_figure(&[a.clone(), b.clone()], &traj, &st, "two runs").unwrap();
        let ts = dir.path().join(format!("timeseries.{}", f.extension()));
        timeseries_figure(
            &[a.clone(), b.clone()],
            &ts,
            &st,
            "two runs",
            Panels::default(),
        )
        .unwrap();
        let map = dir.path().join(format!("map.{}", f.extension()));
        field_map(&a.scenario, [-20.0, 20.0, -20.0, 20.0], &map, &st, "map").unwrap();
        match f {
            Format::Png => {
                check_png(&traj, 1100, 900);
                check_png(&ts, 1100, 980);
                check_png(&map, 1100, 900);
            }
            Format::Svg => {
                check_svg(
                    &traj,
                    560,
                    &[
                        "x, east (m)",
                        "y, north (m)",
                        "isoline s_d = 10",
                        "\na\n</text>",
                        "\nb\n</text>",
                    ],
                );
                check_svg(&ts, 560, &["time (s)", "steady-state window"]);
                check_svg(&map, 560, &["field value"]);
            }
        }
    }
}

/// The SVG's `<text>` contents (tick labels, titles, legends).
fn svg_texts(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap();
    text.split("<text")
        .skip(1)
        .filter_map(|t| {
            let body = t.split_once('>')?.1;
            Some(body.split("</text>").next()?.trim().to_string())
        })
        .collect()
}

/// Issue 15 item 6: paper-ready figures. Ticks without a trailing `.0` and never `-0`; Greek
/// symbols; the middle panel says it plots the true s and draws the measured s too when noise
/// is on; the heat map is one embedded image, not thousands of rectangles; a nearly flat field
/// gets distinct colour-bar ticks.
#[test]
fn figures_fit_for_a_paper() {
    let dir = tempfile::tempdir().unwrap();
    let noisy = make_run(
        &dir.path().join("n"),
        &[
            "sim.duration_s=60",
            "sensor.noise_std=0.05",
            "controller.derivative=filtered_difference",
        ],
    );
    let st = Style::new(Format::Svg);
    let ts = dir.path().join("ts.svg");
    timeseries_figure(
        std::slice::from_ref(&noisy),
        &ts,
        &st,
        "noisy",
        Panels::default(),
    )
    .unwrap();
    let texts = svg_texts(&ts);
    for t in &texts {
        let n = t.replace('\u{2212}', "-");
        if n.parse::<f64>().is_ok() {
            assert!(!n.ends_with(".0"), "tick `{t}`");
            assert_ne!(n, "-0", "tick `{t}`");
        }
    }
    let joined = texts.join("|");
    assert!(joined.contains("\u{3b5} = s \u{2212} s_d"), "{joined}");
    assert!(joined.contains("\u{3c9} (rad/s)"), "{joined}");
    assert!(
        joined.contains("s: true (bold), measured (light)"),
        "{joined}"
    );
    // The time axis ends at 60 s: its last tick is drawn.
    assert!(texts.iter().any(|t| t == "60"), "{joined}");
    let traj = dir.path().join("traj.svg");
    trajectory_figure(std::slice::from_ref(&noisy), &traj, &st, "noisy").unwrap();
    let svg = std::fs::read_to_string(&traj).unwrap();
    assert_eq!(
        svg.matches("<image").count(),
        1,
        "the heat map is one image"
    );
    assert!(
        svg.matches("<rect").count() < 300,
        "{} rects",
        svg.matches("<rect").count()
    );
    assert!(svg.len() < 400_000, "{} bytes", svg.len());
    // A nearly flat field: 10 .. 10.001 over the map; the colour-bar ticks differ.
    let flat = make_run(
        &dir.path().join("f"),
        &[
            "field.kind=linear_ramp",
            "field.offset=10.0",
            "field.gradient_per_m=[0.0, 0.00001]",
            "controller.level=10.00005",
            "initial.x_m=0.0",
            "initial.y_m=0.0",
            "sim.duration_s=5",
        ],
    );
    let map = dir.path().join("flat.svg");
    field_map(
        &flat.scenario,
        [-50.0, 50.0, -50.0, 50.0],
        &map,
        &st,
        "flat",
    )
    .unwrap();
    let ticks: Vec<String> = svg_texts(&map)
        .into_iter()
        .filter(|t| t.starts_with("10.000"))
        .collect();
    let distinct: std::collections::BTreeSet<&String> = ticks.iter().collect();
    assert!(
        ticks.len() >= 3 && distinct.len() == ticks.len(),
        "{ticks:?}"
    );
}

/// Issue 15 item 7: `--size`, `--dpi`, `--font-size`, `--title`, `--colormap` act on the image.
#[test]
fn figure_options_act() {
    let dir = tempfile::tempdir().unwrap();
    let a = make_run(&dir.path().join("a"), &["sim.duration_s=30"]);
    let mut st = Style::new(Format::Png);
    st.size_px = Some((800, 600));
    st.dpi = 200.0;
    st.colormap = Colormap::Gray;
    let p = dir.path().join("t.png");
    trajectory_figure(std::slice::from_ref(&a), &p, &st, "t").unwrap();
    check_png(&p, 1600, 1200);
    // Grey scale: the heat map's pixels have r = g = b (the lines are coloured).
    let img = image::open(&p).unwrap().to_rgb8();
    let grey = img
        .pixels()
        .filter(|px| px.0[0] == px.0[1] && px.0[1] == px.0[2])
        .count();
    assert!(grey as f64 > 0.5 * (1600.0 * 1200.0), "{grey}");
    // --font-size scales every text by the same factor (20 px against the SVG default 13).
    let max_font = |font: Option<f64>, title: Option<String>| {
        let mut st = Style::new(Format::Svg);
        st.title = title;
        st.font_px = font;
        let p = dir.path().join("t.svg");
        timeseries_figure(
            std::slice::from_ref(&a),
            &p,
            &st,
            "a default title",
            Panels::default(),
        )
        .unwrap();
        let svg = std::fs::read_to_string(&p).unwrap();
        let max = svg
            .split("font-size=\"")
            .skip(1)
            .filter_map(|t| t.split('"').next()?.parse::<f64>().ok())
            .fold(0.0, f64::max);
        (max, svg)
    };
    let (base, svg) = max_font(None, None);
    assert!(svg.contains("a default title"));
    let (big, svg) = max_font(Some(20.0), Some(String::new()));
    assert!(
        !svg.contains("a default title"),
        "--title \"\" drops the title"
    );
    // Without the title the largest text is a label (1.0 x base) instead of the title (1.6 x).
    let want = 20.0 / 13.0 * 1.0 / 1.6;
    assert!(
        (big / base - want).abs() < 0.05 * want,
        "{big} / {base} vs {want}"
    );
}

#[test]
fn a_directory_without_a_run_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let e = RunData::load(dir.path()).unwrap_err().to_string();
    assert!(e.contains("summary.json"), "{e}");
}

/// A text element of an SVG: (x, font size, text-anchor, rotated, content).
fn svg_text_boxes(svg: &str) -> Vec<(f64, f64, String, bool, String)> {
    let attr = |tag: &str, name: &str| -> Option<String> {
        let at = tag.find(&format!(" {name}=\""))? + name.len() + 3;
        Some(tag[at..at + tag[at..].find('"')?].to_string())
    };
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let (tag, rest) = t.split_once('>')?;
            Some((
                attr(tag, "x")?.parse().ok()?,
                attr(tag, "font-size")?.parse().ok()?,
                attr(tag, "text-anchor").unwrap_or_default(),
                tag.contains("rotate("),
                rest.split("</text>").next()?.trim().to_string(),
            ))
        })
        .collect()
}

/// Width of a number in DejaVu Sans, in ems, from the font's advance widths in its 2048
/// units per em (digits 1303, '.' 651, '-' 739, 'e' 1260): independent of plotters' layout.
fn dejavu_number_em(s: &str) -> f64 {
    s.chars()
        .map(|c| match c {
            '0'..='9' => 1303.0,
            '.' => 651.0,
            '-' | '\u{2212}' => 739.0,
            'e' => 1260.0,
            _ => 1434.0,
        })
        .sum::<f64>()
        / 2048.0
}

/// Issue 30 item 12, nu36-1: colour-bar tick labels as wide as `-12344.9975` (a field of
/// -12345 with a 1e-4 per metre slope) fit between the bar and its unit, drawn rotated at the
/// image's right edge: each label starts right of the bar and its right end (its left end plus
/// its width in the font's metrics) is left of the unit's glyphs, the unit inside the image.
/// (The old fixed 4.6-font-size area put these labels over the unit; nu36-1's PNGs drew the
/// bar over labels anchored at their right end.)
#[test]
fn wide_colour_bar_labels_fit_between_unit_and_bar() {
    let dir = tempfile::tempdir().unwrap();
    let run = make_run(
        &dir.path().join("w"),
        &[
            "field.kind=linear_ramp",
            "field.offset=-12345.0",
            "field.gradient_per_m=[0.0001, 0.00005]",
            "field.units=\"kelvin above absolute zero\"",
            "controller.level=-12344.9995",
            "initial.x_m=0.0",
            "initial.y_m=0.0",
            "sim.duration_s=5",
        ],
    );
    for (w, h) in [(560, 460), (420, 340)] {
        let mut st = Style::new(Format::Svg);
        st.size_px = Some((w, h));
        let path = dir.path().join(format!("w{w}.svg"));
        field_map(&run.scenario, [-15.0, 15.0, -5.0, 25.0], &path, &st, "wide").unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        let texts = svg_text_boxes(&svg);
        let unit = texts
            .iter()
            .find(|t| t.4 == "kelvin above absolute zero")
            .expect("the bar's unit");
        assert!(unit.3, "the unit is drawn rotated");
        // The level in the legend, every digit (a tick label would give -12344.999).
        assert!(
            texts.iter().any(|t| t.4 == "isoline s_d = -12344.9995"),
            "{texts:?}"
        );
        // nu36-1: the bar, then its tick labels left-aligned right of it, then the unit,
        // rotated at the right edge. Rotated a quarter turn clockwise with its baseline moved
        // 0.76 em off its anchor, the unit's glyphs span about one font size left of the anchor
        // (1.2 allowed, as the ascent and descent of the face).
        let (unit_left, unit_right) = (unit.0 - 1.2 * unit.1, unit.0);
        assert!(
            unit_right <= w as f64,
            "{w}: the unit at {unit_right} beyond the image"
        );
        let labels: Vec<_> = texts
            .iter()
            .filter(|t| t.2 == "start" && !t.3 && t.4.starts_with("-1234"))
            .collect();
        assert!(labels.len() >= 3, "{texts:?}");
        let labels_left = labels.iter().map(|l| l.0).fold(f64::INFINITY, f64::min);
        // The bar: the colour rectangles just left of the labels.
        let bar_x = svg
            .split("<rect")
            .filter_map(|r| {
                let x: f64 = r.split(" x=\"").nth(1)?.split('"').next()?.parse().ok()?;
                let width: f64 = r
                    .split(" width=\"")
                    .nth(1)?
                    .split('"')
                    .next()?
                    .parse()
                    .ok()?;
                (x > w as f64 / 2.0 && x < labels_left && width < 60.0).then_some((x, x + width))
            })
            .fold((f64::INFINITY, 0.0f64), |(a, b), (x0, x1)| {
                (a.min(x0), b.max(x1))
            });
        assert!(bar_x.0 < bar_x.1, "{w}: no bar left of the labels");
        for l in &labels {
            let right = l.0 + dejavu_number_em(&l.4) * l.1;
            assert!(
                l.0 >= bar_x.1,
                "{w}: {:?} starts at {} inside the bar ending at {}",
                l.4,
                l.0,
                bar_x.1
            );
            assert!(
                right <= unit_left,
                "{w}: {:?} ends at {right:.1}, the unit starts at {unit_left:.1}",
                l.4
            );
        }
    }
}

/// att46-17: a figure of many paths (here 100 starts along the level-10 circle of radius
/// 6.93 m) had a white ring of 7 px round every start, a white band over the isoline and the
/// tracks. Beyond 16 paths no ring is drawn (no white-stroked circle in the SVG) and each
/// start dot's radius is at most `7 sqrt(16/100) = 2.8` px, rounded to 3: the 100 dots cover
/// at most the area of 16 full ones.
#[test]
fn many_paths_have_small_start_marks_without_white_rings() {
    let dir = tempfile::tempdir().unwrap();
    // The level-10 isoline of F = 20 exp(-0.1 r): r = ln(2) / 0.1.
    let r = 2f64.ln() / 0.1;
    let n = 100;
    let runs: Vec<RunData> = (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            let sets = [
                "sim.duration_s=2".to_string(),
                format!("initial.x_m={}", r * a.cos()),
                format!("initial.y_m={}", r * a.sin()),
                format!("initial.heading_rad={}", a - std::f64::consts::FRAC_PI_2),
            ];
            let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
            make_run(&dir.path().join(format!("r{i}")), &sets)
        })
        .collect();
    let svg_path = dir.path().join("many.svg");
    trajectory_figure(&runs, &svg_path, &Style::new(Format::Svg), "many").unwrap();
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    let circles: Vec<&str> = svg
        .split("<circle")
        .skip(1)
        .map(|c| c.split('>').next().unwrap())
        .collect();
    assert_eq!(circles.len(), n, "one start dot a path, no ring");
    for c in &circles {
        assert!(!c.contains("#FFFFFF"), "a white ring: {c}");
        let r: f64 = c
            .split("r=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!(r <= 3.0, "start dot of {r} px");
    }
    // Two paths keep their full marks: a dot and a white ring of 7 px each.
    let two = dir.path().join("two.svg");
    trajectory_figure(&runs[..2], &two, &Style::new(Format::Svg), "two").unwrap();
    let svg = std::fs::read_to_string(&two).unwrap();
    let circles: Vec<&str> = svg
        .split("<circle")
        .skip(1)
        .map(|c| c.split('>').next().unwrap())
        .collect();
    assert_eq!(circles.len(), 4);
    assert_eq!(circles.iter().filter(|c| c.contains("#FFFFFF")).count(), 2);
}

/// The longest run of `true` in `flags`: `(first, last)` index.
fn longest_run(flags: impl Iterator<Item = bool>) -> (u32, u32) {
    let (mut best, mut start, mut len) = ((0, 0), 0, 0u32);
    for (i, f) in flags.enumerate() {
        let i = i as u32;
        if f {
            if len == 0 {
                start = i;
            }
            len += 1;
            if len > best.1 - best.0 + 1 || best == (0, 0) {
                best = (start, i);
            }
        } else {
            len = 0;
        }
    }
    best
}

/// The plotting rectangle `(left, top, right, bottom)` of a one-panel PNG: its x axis is the
/// row with the most black pixels, its y axis the column with the most; the rectangle spans
/// the longest black run of each.
fn plot_rect(img: &image::RgbImage) -> (u32, u32, u32, u32) {
    let black = |x: u32, y: u32| img.get_pixel(x, y).0 == [0, 0, 0];
    let (w, h) = img.dimensions();
    let bottom = (0..h)
        .max_by_key(|&y| (0..w).filter(|&x| black(x, y)).count())
        .unwrap();
    let left = (0..w)
        .max_by_key(|&x| (0..h).filter(|&y| black(x, y)).count())
        .unwrap();
    let (x0, x1) = longest_run((0..w).map(|x| black(x, bottom)));
    let (y0, y1) = longest_run((0..h).map(|y| black(left, y)));
    (x0.min(left), y0, x1, y1.max(bottom))
}

/// att49-1: a genuine run at `controller.kp = 1e300` (600 s, as att49 ran it) flips its turn rate between about
/// +-1e300 from one step to the next, drawn at the +-1e100 bound (the panel's top and bottom
/// less its 8 % padding). plotters joined each near reversal of the 2-pixel line with edges
/// meeting far past the corner, so the PNG's strokes ran over the panels above and off the
/// image (the SVG stayed inside). No pixel of the run's colour may lie outside the panel's
/// plotting rectangle, and the series is drawn (the colour is there).
#[test]
fn a_clipped_turn_rate_stays_inside_its_png_panel() {
    let dir = tempfile::tempdir().unwrap();
    let run = make_run(&dir.path().join("kp"), &["controller.kp=1e300"]);
    assert!(
        run.trace.iter().any(|t| t.omega_radps.abs() > 1e100),
        "the run does not pass the bound"
    );
    let omega_only = Panels {
        error: false,
        measurement: false,
        measurement_rate: false,
        omega: true,
    };
    for size in [None, Some((600, 800))] {
        let mut st = Style::new(Format::Png);
        st.size_px = size;
        let png = dir.path().join("ts.png");
        timeseries_figure(std::slice::from_ref(&run), &png, &st, "", omega_only).unwrap();
        let img = image::open(&png).unwrap().to_rgb8();
        // The 2-pixel line may cover the axis it starts on: two pixels of slack.
        let (left, top, right, bottom) = plot_rect(&img);
        let (left, top, right, bottom) = (left - 2, top - 2, right + 2, bottom + 2);
        assert!(
            right > left + 100 && bottom > top + 100,
            "{size:?}: no plot found"
        );
        let run_colour = [214, 39, 40];
        let mut inside = 0;
        for (x, y, p) in img.enumerate_pixels() {
            if p.0 != run_colour {
                continue;
            }
            assert!(
                (left..=right).contains(&x) && (top..=bottom).contains(&y),
                "{size:?}: the series at ({x}, {y}), outside the panel ({left}, {top})..({right}, {bottom})"
            );
            inside += 1;
        }
        assert!(
            inside > 100,
            "{size:?}: the series is not drawn ({inside} pixels)"
        );
    }
}

/// att49-8: a run whose error is past the clip bound for the whole run draws a flat line at
/// 1e100; its axis spanned 1e-8 of the bound, labelled "1.00000004e100" .. "9.9999995e99",
/// which ran off the figure over the axis label. A flat panel now spans a tenth of its value
/// (matplotlib's `nonsingular`, 5 % each side): ticks 2e98 apart (tick_step of 1.16e99 over
/// ten ticks), each label at most "1.04e100", one of them the bound itself.
#[test]
fn a_panel_flat_at_the_clip_bound_gets_readable_ticks() {
    let dir = tempfile::tempdir().unwrap();
    let run = make_run(
        &dir.path().join("big"),
        &[
            "field.i0=1e100",
            "controller.level=-9e99",
            "sim.duration_s=20",
        ],
    );
    assert!(
        run.trace.iter().all(|t| t.error.abs() > 1e100),
        "the error is not past the bound the whole run"
    );
    let error_only = Panels {
        error: true,
        measurement: false,
        measurement_rate: false,
        omega: false,
    };
    let svg = dir.path().join("ts.svg");
    timeseries_figure(
        std::slice::from_ref(&run),
        &svg,
        &Style::new(Format::Svg),
        "",
        error_only,
    )
    .unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    let labels: Vec<&str> = text
        .split("<text")
        .skip(1)
        .filter_map(|t| t.split_once('>').and_then(|(_, r)| r.split_once("</text>")))
        .map(|(l, _)| l.trim())
        .filter(|l| l.contains("e99") || l.contains("e100"))
        .collect();
    assert!(
        labels.contains(&"1e100"),
        "no tick at the bound: {labels:?}"
    );
    for l in &labels {
        assert!(
            l.len() <= 8 || l.starts_with("error"),
            "a tick label too long to read: {l:?} in {labels:?}"
        );
    }
}
