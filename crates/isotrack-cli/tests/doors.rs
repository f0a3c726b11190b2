//! Issue 30's last new-user and hostile findings at the CLI's doors: `compare`'s field bounds
//! and fairness, `plot` / `report` of runs over different fields, a sensor rate that is no whole
//! number of steps, the report's map (axes, colour bar, dashed isoline).

mod browser;
mod common;
use browser::{assert_no_script_error, chromium, load};
use common::{assert_fails, isotrack, stderr, write};
use std::path::Path;

fn scenario(name: &str) -> String {
    format!("{}/../../scenarios/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The number after `what` in `text` (up to the next space, `:` or `,`).
fn number_after(text: &str, what: &str) -> f64 {
    let at = text
        .find(what)
        .unwrap_or_else(|| panic!("no `{what}` in: {text}"))
        + what.len();
    let word: String = text[at..]
        .chars()
        .take_while(|c| !matches!(c, ' ' | ':' | ',' | ';' | ')'))
        .collect();
    word.parse()
        .unwrap_or_else(|_| panic!("`{what}` is followed by `{word}`, not a number: {text}"))
}

/// The new-user finding: on gaussian-plumes-pm25, `check` printed `gamma1 = 0.038868` for the
/// tube |F - s_d| <= 1 while `compare` warned `v*min|grad F| = 0.0000` for the sliding mode,
/// whose tube (its linear zone delta = 1) is the same: two lattices, one number. Now the
/// warning names its tube and gives the check's bounds: `gamma1` equals the `tube_gamma1` of
/// `check --tube-halfwidth delta` (to the six digits printed), `v*gamma1` is 0.5 m/s times it,
/// for delta = 1 and for delta = 0.5.
#[test]
fn compare_and_check_bound_the_same_tube_with_one_computation() {
    let scen = scenario("gaussian-plumes-pm25.toml");
    // (delta = 0.5 gives gamma1 = 0.378, v gamma1 = 0.189: gamma = 1 (mu = 0.5) breaks (a).)
    for (delta, gamma) in [("1", "0.2"), ("0.5", "1")] {
        let o = isotrack(&[
            "compare",
            &scen,
            "--controllers",
            "sliding_mode",
            "--gain",
            &format!("sliding_mode.delta={delta}"),
            "--gain",
            &format!("sliding_mode.gamma={gamma}"),
            "--set",
            "sim.duration_s=1",
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let e = stderr(&o);
        let w = e
            .lines()
            .find(|l| l.starts_with("warning: sliding_mode:"))
            .unwrap_or_else(|| panic!("no sliding-mode warning: {e}"));
        assert!(
            w.contains(&format!("over the tube |F - s_d| <= {delta} (delta"))
                && w.contains(&format!("isotrack check --tube-halfwidth {delta}")),
            "{w}"
        );
        let o = isotrack(&["check", &scen, "--json", "--tube-halfwidth", delta]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let tube_gamma1 = j["prop2"]["tube_gamma1"].as_f64().unwrap();
        assert!(tube_gamma1 > 0.01, "{tube_gamma1}");
        let gamma1 = number_after(w, "; gamma1 = ");
        assert!(
            (gamma1 / tube_gamma1 - 1.0).abs() < 1e-5,
            "compare's gamma1 {gamma1} vs check's tube_gamma1 {tube_gamma1}: {w}"
        );
        let v_gamma1 = number_after(w, "v*gamma1 = ");
        assert!(
            (v_gamma1 / (0.5 * tube_gamma1) - 1.0).abs() < 1e-5,
            "{v_gamma1} vs 0.5 x {tube_gamma1}"
        );
        for key in ["gamma2", "gamma3"] {
            let c = number_after(w, &format!("{key} = "));
            let want = j["prop2"][format!("tube_{key}")].as_f64().unwrap();
            assert!((c / want - 1.0).abs() < 1e-5, "{key}: {c} vs {want}: {w}");
        }
    }
}

/// A 5 m Gaussian plume 60 m from the start: `F(r) = 10 exp(-r^2/50)` is the level 5 at
/// `r = sqrt(50 ln 2) = 5.89 m`, 54 m away, farther than 0.5 m/s carries a vehicle in 100 s
/// (50 m): no law can reach the isoline, every row must say so (by theory, not by the run),
/// and pid_crossing (which acts only at crossings) flies exactly as pid.
const FAR_PLUME: &str = "[field]\nkind = \"gaussian_plumes\"\nbackground = 0.0\nsources = [{ center_m = [0.0, 0.0], amplitude = 10.0, sigma_m = [5.0, 5.0], rotation_rad = 0.0 }]\n[initial]\nx_m = 60.0\ny_m = 0.0\n[controller]\nlevel = 5.0\n[sim]\nduration_s = 100.0\n";

/// The fairness finding: from a flat start every baseline circled with no word in the table
/// (pid's effort 2.9e8), pid and pid_crossing gave identical rows without a reason, and only
/// the paper's law flew the scenario's search. Now each row that never reached the isoline says
/// so, the note under the table says why and how far each went (circling: within a turning
/// diameter, 2 v/omega = 1 m at 1 rad/s), and every law flies the scenario's search.
#[test]
fn compare_flags_laws_that_never_reach_the_isoline_and_gives_all_the_search() {
    let d = tempfile::tempdir().unwrap();
    let scen = write(d.path(), "far.toml", FAR_PLUME);
    let out = d.path().join("cmp");
    let o = isotrack(&[
        "compare",
        &scen,
        "--set",
        "controller.max_turn_rate_radps=1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout);
    let laws = [
        "pi_isoline",
        "sliding_mode",
        "sliding_mode_smooth",
        "suboptimal_sosm",
        "pid",
        "pid_crossing",
        "gradient_reference",
    ];
    for law in laws {
        let row = table
            .lines()
            .find(|l| l.starts_with(&format!("| {law} ")))
            .unwrap_or_else(|| panic!("no row {law}: {table}"));
        assert!(row.contains("| completed, never reached s_d |"), "{row}");
        let far = number_after(&table, &format!("- {law}: at most "));
        assert!(far <= 50.0 + 1e-6, "{law} went {far} m in 100 s at 0.5 m/s");
    }
    assert!(
        table.contains("pid_crossing: at most")
            && table.contains("(the same run as pid: pid_crossing adds its turn only at a crossing of the level, and there was none)"),
        "{table}"
    );
    assert!(table.contains("controller.search"), "{table}");
    // The CSV keeps its documented outcome values.
    let csv = std::fs::read_to_string(out.join("comparison.csv")).unwrap();
    assert!(
        csv.lines()
            .skip(1)
            .all(|l| l.split(',').nth(1) == Some("completed")),
        "{csv}"
    );

    // With a search, every law flies it (not only the scenario's own law).
    let out = d.path().join("cmp-search");
    let o = isotrack(&[
        "compare",
        &scen,
        "--set",
        "controller.search=spiral",
        "--set",
        "controller.search_handover=0.5",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    for law in laws {
        let t = std::fs::read_to_string(out.join(law).join("scenario.toml")).unwrap();
        let t: toml::Table = toml::from_str(&t).unwrap();
        assert_eq!(
            (
                t["controller"]["search"].as_str(),
                t["controller"]["search_handover"].as_float()
            ),
            (Some("spiral"), Some(0.5)),
            "{law}"
        );
    }
}

/// Runs `scenario` with `sets` into `dir`.
fn run_into(scenario: &str, dir: &Path, sets: &[&str]) {
    let mut args = vec!["run", scenario, "--out", dir.to_str().unwrap(), "-q"];
    for s in sets {
        args.extend(["--set", s]);
    }
    let o = isotrack(&args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// The hostile finding: `plot` and `report` drew runs of different fields (or isolines) over
/// the first run's field without a word. Both now refuse (65) naming both runs and the first
/// key that differs; runs over one field (other starts, other gains) still plot together.
#[test]
fn plot_and_report_refuse_runs_over_different_fields() {
    let d = tempfile::tempdir().unwrap();
    let scen = scenario("paper-fig2b-circular.toml");
    let dir = |n: &str| d.path().join(n);
    run_into(&scen, &dir("base"), &["sim.duration_s=20"]);
    run_into(&scen, &dir("hotter"), &["sim.duration_s=20", "field.i0=30"]);
    run_into(
        &scen,
        &dir("level12"),
        &["sim.duration_s=20", "controller.level=12"],
    );
    run_into(
        &scen,
        &dir("other-start"),
        &["sim.duration_s=20", "initial.x_m=12", "controller.kp=5"],
    );
    let s = |p: std::path::PathBuf| p.to_str().unwrap().to_string();
    for (other, key) in [
        ("hotter", "field.i0: 20.0 in base, 30.0 in hotter"),
        ("level12", "controller.level: 10.0 in base, 12.0 in level12"),
    ] {
        let o = isotrack(&[
            "plot",
            &s(dir("base")),
            &s(dir(other)),
            "--out",
            &s(dir("figs")),
        ]);
        assert_fails(
            &o,
            65,
            &[&s(dir("base")), &s(dir(other)), key, "different fields"],
        );
        let page = dir("r.html");
        let o = isotrack(&[
            "report",
            &s(dir("base")),
            &s(dir(other)),
            "--out",
            &s(page.clone()),
        ]);
        assert_fails(&o, 65, &[&s(dir("base")), &s(dir(other)), key]);
        assert!(!page.exists());
    }
    let o = isotrack(&[
        "plot",
        &s(dir("base")),
        &s(dir("other-start")),
        "--out",
        &s(dir("figs")),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = isotrack(&[
        "report",
        &s(dir("base")),
        &s(dir("other-start")),
        "--out",
        &s(dir("ok.html")),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// `--set sensor.rate_hz=3` at dt = 0.01 s (33.3 steps a period) names the valid rates either
/// side, 1/0.34 s and 1/0.33 s, each written so that typing it back is accepted.
#[test]
fn an_invalid_sensor_rate_names_the_nearest_valid_rates() {
    let o = isotrack(&["run", "--set", "sensor.rate_hz=3"]);
    assert_fails(&o, 65, &["sensor.rate_hz", "nearest valid rates are"]);
    let e = stderr(&o);
    let lo = number_after(&e, "nearest valid rates are ");
    let hi = number_after(&e[e.find("s) and ").expect(&e)..], "s) and ");
    assert!(
        (lo * 0.34 - 1.0).abs() < 1e-9 && (hi * 0.33 - 1.0).abs() < 1e-9,
        "{e}"
    );
    for r in [lo, hi] {
        let o = isotrack(&[
            "run",
            "--set",
            &format!("sensor.rate_hz={r}"),
            "--set",
            "sim.duration_s=1",
            "-q",
        ]);
        assert_eq!(o.status.code(), Some(0), "{r}: {}", stderr(&o));
    }
}

/// The report's map: axes in metres and a colour bar in the field's units, and an isoline whose
/// dashes show. The page's own drawing function is called on a picture made here: the field
/// `20 exp(-0.1 r)` on [-10, 10]^2 and its level-10 isoline, the circle r = 10 ln 2, as 240
/// chords in shuffled order, half of them reversed (as marching squares leave them). Nice ticks
/// of a 20 m span are every 5 m, of [0, 20] every 5; the chords join into one closed line; and
/// along the circle white dashes alternate with gaps (a solid line is white all round: each
/// 4 px chord restarted the dash pattern, so only its first 6 px "on" part was ever drawn).
#[test]
fn report_map_has_axes_a_colour_bar_and_a_dashed_isoline() {
    let Some(browser) = chromium() else { return };
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("run");
    run_into(
        &scenario("paper-fig2b-circular.toml"),
        &run,
        &["sim.duration_s=30", "field.units=\"ppm\""],
    );
    let page = d.path().join("report.html");
    let o = isotrack(&[
        "report",
        run.to_str().unwrap(),
        "--out",
        page.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let html = std::fs::read_to_string(&page).unwrap();
    let probe = r#"<script>
(function () {
  const n = 81, r = 10 * Math.LN2, values = [], segs = [];
  for (let j = 0; j < n; j++) for (let i = 0; i < n; i++) {
    const x = -10 + 20 * i / (n - 1), y = -10 + 20 * j / (n - 1);
    values.push(20 * Math.exp(-0.1 * Math.hypot(x, y)));
  }
  const m = 240;
  for (let k = 0; k < m; k++) {
    const a = 2 * Math.PI * k / m, b = 2 * Math.PI * (k + 1) / m;
    const s = [r * Math.cos(a), r * Math.sin(a), r * Math.cos(b), r * Math.sin(b)];
    segs.push(k % 2 ? [s[2], s[3], s[0], s[1]] : s);
  }
  for (let k = m - 1; k > 0; k--) { const q = (k * 7919) % (k + 1); const t = segs[k]; segs[k] = segs[q]; segs[q] = t; }
  const c = document.createElement("canvas"); c.width = 628; c.height = 518; c.id = "probe";
  c.getContext("2d", { willReadFrequently: true });
  document.body.appendChild(c);
  const pic = { bounds_m: [-10, -10, 10, 10], n: n, values: values, isoline: segs, level: 10, range: [0, 20] };
  const toPx = drawField(c, pic, { units: "ppm" });
  const ctx = c.getContext("2d");
  let white = 0, total = 0;
  for (let k = 0; k < 1440; k++) {
    const a = 2 * Math.PI * k / 1440, p = toPx(r * Math.cos(a), r * Math.sin(a));
    const px = ctx.getImageData(Math.round(p[0]) - 1, Math.round(p[1]) - 1, 3, 3).data;
    let w = false;
    for (let q = 0; q < 36; q += 4) if (px[q] > 225 && px[q + 1] > 225 && px[q + 2] > 225) w = true;
    total++; if (w) white++;
  }
  c.dataset.whiteFraction = (white / total).toFixed(3);
  c.dataset.area = toPx.area.join(",");
})();
</script></body>"#;
    let probed = d.path().join("probed.html");
    std::fs::write(&probed, html.replacen("</body>", probe, 1)).unwrap();
    let (dom, log) = load(
        &browser,
        &probed,
        &d.path().join("profile"),
        &["--dump-dom"],
    );
    assert_no_script_error(&log);
    assert!(dom.contains("data-ready=\"1\""), "{log}");
    let attr = |id: &str, name: &str| -> String {
        let at = dom
            .find(&format!("id=\"{id}\""))
            .unwrap_or_else(|| panic!("no #{id}"));
        let tag_start = dom[..at].rfind('<').unwrap();
        let tag = &dom[tag_start..tag_start + dom[tag_start..].find('>').unwrap()];
        let key = format!("{name}=\"");
        let v = tag
            .find(&key)
            .unwrap_or_else(|| panic!("#{id} has no {name}: {tag}"))
            + key.len();
        tag[v..v + tag[v..].find('"').unwrap()].to_string()
    };
    assert_eq!(attr("probe", "data-x-ticks"), "-10 -5 0 5 10");
    assert_eq!(attr("probe", "data-y-ticks"), "-10 -5 0 5 10");
    assert_eq!(attr("probe", "data-colour-ticks"), "0 5 10 15 20");
    assert_eq!(attr("probe", "data-colour-label"), "field (ppm)");
    assert_eq!(attr("probe", "data-isoline-lines"), "1");
    let white: f64 = attr("probe", "data-white-fraction").parse().unwrap();
    assert!(
        // White within a pixel of the circle: all round for a solid line (the drawing before
        // the fix: 1.000), about the dashes' share (7 px of every 12, widened by a pixel at
        // each end) with gaps.
        (0.35..0.9).contains(&white),
        "white along the isoline: {white}"
    );
    // The page's own map: its axes are in metres round the run's square, its colour bar in ppm.
    assert_eq!(attr("map", "data-colour-label"), "field (ppm)");
    let xt = attr("map", "data-x-ticks");
    assert!(xt.split(' ').count() >= 3, "{xt}");
    assert!(attr("map", "aria-label").contains("colour field (ppm)"));
}

/// Issue 30 (doors30a), item 1: a tiny or huge float is written in its shortest round-trip
/// form, never 300 digits: `1e-300` in `isotrack show`, in a run's `scenario.toml` and in a
/// sweep's `results.csv` cell and `base_scenario.toml`; each reads back as the same `f64`, bit
/// for bit.
#[test]
fn tiny_floats_are_written_short_and_read_back_exactly() {
    let d = tempfile::tempdir().unwrap();
    let tiny = 1e-300_f64;
    let set = "initial.x_m=1e-300";
    let read_x = |text: &str| -> f64 {
        let t: toml::Table = toml::from_str(text).unwrap();
        t["initial"]["x_m"].as_float().unwrap()
    };
    let o = isotrack(&["show", "--set", set]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let shown = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(shown.contains("x_m = 1e-300\n"), "{shown}");
    assert!(shown.lines().all(|l| l.len() < 200), "{shown}");
    assert_eq!(read_x(&shown).to_bits(), tiny.to_bits());
    let run = d.path().join("run");
    run_into(
        &scenario("paper-fig2b-circular.toml"),
        &run,
        &["sim.duration_s=1", set],
    );
    let written = std::fs::read_to_string(run.join("scenario.toml")).unwrap();
    assert!(written.contains("x_m = 1e-300\n"), "{written}");
    assert_eq!(read_x(&written).to_bits(), tiny.to_bits());
    let sw = write(
        d.path(),
        "s.toml",
        &format!(
            "scenario = {:?}\n[base]\nsim.duration_s = 1.0\ncontroller.kp = 1e20\n[grid]\ninitial.x_m = [1e-300, 0.5]\n",
            scenario("paper-fig2b-circular.toml")
        ),
    );
    let out = d.path().join("sweep");
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    assert!(matches!(o.status.code(), Some(0 | 65)), "{}", stderr(&o));
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let cell = csv
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .nth(1)
        .unwrap()
        .to_string();
    assert_eq!(cell, "1e-300", "{csv}");
    assert_eq!(cell.parse::<f64>().unwrap().to_bits(), tiny.to_bits());
    let base = std::fs::read_to_string(out.join("base_scenario.toml")).unwrap();
    assert!(base.contains("kp = 1e20\n"), "{base}");
    assert!(base.len() < 4000, "{} bytes", base.len());
    // A resume reads the same cells back.
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap(), "--resume"]);
    assert!(matches!(o.status.code(), Some(0 | 65)), "{}", stderr(&o));
    assert!(!stderr(&o).contains("damaged"), "{}", stderr(&o));
}

/// Issue 30 (doors30a), item 3: `compare`'s "never reached" flag comes from the run's own
/// metrics (every step), not from the trace's rows: with the trace off
/// (`output.record_rate_hz = 0`) every law that circles from the far start is still flagged,
/// with how far it went.
#[test]
fn compare_flags_never_reached_whatever_the_record_rate() {
    let d = tempfile::tempdir().unwrap();
    let scen = write(d.path(), "far.toml", FAR_PLUME);
    for rate in ["0", "0.1"] {
        let o = isotrack(&[
            "compare",
            &scen,
            "--controllers",
            "pi_isoline,pid",
            "--set",
            "controller.max_turn_rate_radps=1",
            "--set",
            &format!("output.record_rate_hz={rate}"),
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let table = String::from_utf8_lossy(&o.stdout);
        for law in ["pi_isoline", "pid"] {
            let row = table
                .lines()
                .find(|l| l.starts_with(&format!("| {law} ")))
                .unwrap_or_else(|| panic!("no row {law}: {table}"));
            assert!(
                row.contains("| completed, never reached s_d |"),
                "rate {rate}: {row}"
            );
            let far = number_after(&table, &format!("- {law}: at most "));
            // Circling at 1 rad/s and 0.5 m/s: within a turning diameter, 1 m, of the start.
            assert!(far > 0.0 && far <= 1.0 + 1e-9, "{law} went {far} m");
        }
    }
}

/// Issue 30 (doors30a), item 4: a puff plume without meander is one field whatever its seed
/// (and its meander's correlation time): `report` and `plot` draw such runs together; with a
/// meander, another seed is another field, refused naming `sim.seed`.
#[test]
fn puff_runs_without_meander_differ_only_in_seed_and_draw_together() {
    let d = tempfile::tempdir().unwrap();
    let scen = scenario("puff-plume-edge.toml");
    let dir = |n: &str| d.path().join(n).display().to_string();
    let calm = ["sim.duration_s=2", "field.meander_std_mps=0"];
    run_into(
        &scen,
        &d.path().join("a"),
        &[&calm[..], &["sim.seed=1"]].concat(),
    );
    run_into(
        &scen,
        &d.path().join("b"),
        &[&calm[..], &["sim.seed=2", "field.meander_correlation_s=5"]].concat(),
    );
    let o = isotrack(&["report", &dir("a"), &dir("b"), "--out", &dir("r.html")]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = isotrack(&["plot", &dir("a"), &dir("b"), "--out", &dir("figs")]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    run_into(
        &scen,
        &d.path().join("m1"),
        &["sim.duration_s=2", "sim.seed=1"],
    );
    run_into(
        &scen,
        &d.path().join("m2"),
        &["sim.duration_s=2", "sim.seed=2"],
    );
    let o = isotrack(&["report", &dir("m1"), &dir("m2"), "--out", &dir("r2.html")]);
    assert_fails(&o, 65, &["sim.seed: 1 in m1, 2 in m2", "different fields"]);
}

/// Issue 30 (doors30a), item 6: a field file overwritten in place (same path, other content)
/// between two runs makes them runs over different fields: each run records its data files'
/// SHA-256 in `summary.json` (`data_files`), and `report`/`plot` refuse runs whose digests
/// differ (65), naming the file.
#[test]
fn a_field_file_overwritten_in_place_is_another_field() {
    let d = tempfile::tempdir().unwrap();
    let src = format!(
        "{}/../../data/no2_germany_kriged/no2_germany_kriged.csv",
        env!("CARGO_MANIFEST_DIR")
    );
    let original = std::fs::read_to_string(&src).unwrap();
    let grid = d.path().join("grid.csv");
    std::fs::write(&grid, &original).unwrap();
    let scen = std::fs::read_to_string(scenario("paper-fig2a-field.toml"))
        .unwrap()
        .replace(
            "../data/no2_germany_kriged/no2_germany_kriged.csv",
            "grid.csv",
        );
    let scen = write(d.path(), "s.toml", &scen);
    let dir = |n: &str| d.path().join(n).display().to_string();
    run_into(&scen, &d.path().join("before"), &["sim.duration_s=2"]);
    run_into(&scen, &d.path().join("same"), &["sim.duration_s=2"]);
    // Every value 1 unit higher: the isoline moves.
    let higher: String = original
        .lines()
        .map(|l| {
            l.split(',')
                .map(|c| {
                    c.trim()
                        .parse::<f64>()
                        .map_or(c.to_string(), |v| format!("{}", v + 1.0))
                })
                .collect::<Vec<_>>()
                .join(",")
                + "\n"
        })
        .collect();
    assert_ne!(higher, original);
    std::fs::write(&grid, &higher).unwrap();
    run_into(&scen, &d.path().join("after"), &["sim.duration_s=2"]);
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(d.path().join("after/summary.json")).unwrap(),
    )
    .unwrap();
    let digests = summary["data_files"].as_object().unwrap();
    assert_eq!(digests.len(), 1, "{summary}");
    // The same file, unchanged: drawn together.
    let o = isotrack(&[
        "report",
        &dir("before"),
        &dir("same"),
        "--out",
        &dir("ok.html"),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    for cmd in ["report", "plot"] {
        let o = isotrack(&[
            cmd,
            &dir("before"),
            &dir("after"),
            "--out",
            &dir(&format!("x-{cmd}")),
        ]);
        assert_fails(
            &o,
            65,
            &["grid.csv", "overwritten in place", "different fields"],
        );
    }
}

/// Issue 30 (doors30a), item 7: a subnormal gain (`kp = 1e-310`, a law that never turns) or
/// any other subnormal positive setting is refused naming the key, its value echoed short.
#[test]
fn subnormal_gains_are_refused_naming_the_key() {
    for set in [
        "controller.kp=1e-310",
        "controller.ki=5e-324",
        "controller.c1=1e-308",
    ] {
        let o = isotrack(&["show", "--set", set]);
        let key = set.split('=').next().unwrap();
        let value = set.split('=').nth(1).unwrap();
        assert_fails(&o, 65, &[&format!("`{key}`"), "subnormal", value]);
    }
    let o = isotrack(&["show", "--set", "controller.ki=0.0"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// Issue 30 (doors30a), item 8, found by the hunt: command-line values that must be > 0
/// accepted a subnormal (`fly --timeout-s 1e-310`: a timeout of no time at all;
/// `check --tube-halfwidth 1e-310`, `interpolate --idw-power 1e-310`), and `sitl`/`fly`
/// echoed the value with Rust's `{}`: `--speedup 1e-300` as 300 digits. Each is refused (64)
/// with the value echoed as written.
#[test]
fn subnormal_command_line_values_are_refused_and_echoed_short() {
    let d = tempfile::tempdir().unwrap();
    let link = "udpout:127.0.0.1:9";
    let stations = write(d.path(), "st.csv", "x_m,y_m,value\n0,0,1\n10,0,2\n0,10,3\n");
    let out = d.path().join("g.csv").display().to_string();
    let cases: [(Vec<&str>, &str); 5] = [
        (
            vec!["fly", "--mavlink", link, "--timeout-s", "1e-310"],
            "--timeout-s",
        ),
        (
            vec!["fly", "--mavlink", link, "--max-duration-s", "1e-310"],
            "--max-duration-s",
        ),
        (
            vec!["sitl", "--mavlink", link, "--speedup", "1e-300"],
            "--speedup",
        ),
        (
            vec!["check", "--tube-halfwidth", "1e-310"],
            "--tube-halfwidth",
        ),
        (
            vec![
                "interpolate",
                &stations,
                "--value-column",
                "value",
                "--idw-power",
                "1e-310",
                "--out",
                &out,
            ],
            "--idw-power",
        ),
    ];
    for (args, flag) in cases {
        let o = isotrack(&args);
        let value = args[args.iter().position(|a| *a == flag).unwrap() + 1];
        assert_fails(&o, 64, &[flag, &format!("got {value}")]);
        assert!(stderr(&o).len() < 400, "{}", stderr(&o));
    }
}
