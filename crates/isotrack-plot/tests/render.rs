//! Figures render as valid PNG and SVG images of the expected size with non-trivial content
//! (no pixel-exact comparison).

use isotrack_plot::{field_map, timeseries_figure, trajectory_figure, Format, Panels, RunData};
use isotrack_scenario::parse_scenario;
use isotrack_sim::TraceRow;
use std::path::Path;

fn make_run(dir: &Path, sets: &[&str]) -> RunData {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let s = parse_scenario("", "<test>", &sets).unwrap();
    let mut rows: Vec<TraceRow> = vec![];
    s.run(&mut rows);
    std::fs::create_dir_all(dir).unwrap();
    // The CLI's writers live in isotrack-cli; write the same three files minimally here.
    let mut csv = String::from("t_s,x_m,y_m,heading_rad,s,error,omega_radps,s_measured\n");
    for r in &rows {
        csv += &format!(
            "{:?},{:?},{:?},{:?},{:?},{:?},{:?},{}\n",
            r.t_s,
            r.x_m,
            r.y_m,
            r.heading_rad,
            r.s,
            r.error,
            r.omega_radps,
            r.s_measured.map(|v| format!("{v:?}")).unwrap_or_default()
        );
    }
    std::fs::write(dir.join("trace.csv"), csv).unwrap();
    std::fs::write(dir.join("summary.json"), "{\"outcome\": \"completed\"}").unwrap();
    std::fs::write(
        dir.join("scenario.toml"),
        toml::to_string(s.file()).unwrap(),
    )
    .unwrap();
    RunData::load(dir).unwrap()
}

fn check_png(path: &Path, w: u32, h: u32) {
    let img = image::open(path).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (w, h), "{}", path.display());
    assert!(w >= 800);
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
        let traj = dir.path().join(format!("trajectory.{}", f.extension()));
        trajectory_figure(&[a.clone(), b.clone()], &traj, f, "two runs").unwrap();
        let ts = dir.path().join(format!("timeseries.{}", f.extension()));
        timeseries_figure(
            &[a.clone(), b.clone()],
            &ts,
            f,
            "two runs",
            Panels::default(),
        )
        .unwrap();
        let map = dir.path().join(format!("map.{}", f.extension()));
        field_map(&a.scenario, [-20.0, 20.0, -20.0, 20.0], &map, f, "map").unwrap();
        match f {
            Format::Png => {
                check_png(&traj, 1100, 900);
                check_png(&ts, 1100, 980);
                check_png(&map, 1100, 900);
            }
            Format::Svg => {
                check_svg(
                    &traj,
                    1100,
                    &[
                        "x, east (m)",
                        "y, north (m)",
                        "isoline s_d = 10",
                        "\na\n</text>",
                        "\nb\n</text>",
                    ],
                );
                check_svg(&ts, 1100, &["time (s)", "steady-state window"]);
                check_svg(&map, 1100, &["field value"]);
            }
        }
    }
}

#[test]
fn a_directory_without_a_run_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let e = RunData::load(dir.path()).unwrap_err().to_string();
    assert!(e.contains("summary.json"), "{e}");
}
