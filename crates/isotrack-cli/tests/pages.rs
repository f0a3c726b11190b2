//! The HTML pages against hostile strings, in a real browser (headless Chromium): every string a
//! user controls (suite name, task title, controller name, `field.units`, scenario name, run
//! directory names) carries markup that would break out of the page's data (`<!--<script>`,
//! `</script>`), run a script (`<img onerror>`, `<script>`), or close an attribute or CDATA
//! (quotes, `]]>`). Each page must finish its script (not stay at "loading"), show each string as
//! text, exactly, and run none of them. U+2028/9 (a line end in old JavaScript) no longer reach a
//! page: the one plain-text rule refuses them in every user string (issue 30, att30b item 3;
//! tested below and in `review.rs`), and the page's JSON escapes them anyway (`isotrack-html`'s
//! `script_json_leaves_no_markup_and_round_trips`).

mod browser;
mod common;
use browser::{assert_no_script_error, chromium, load};
use common::{isotrack, stderr};
use isotrack_core::{IsolineController, Measurement};
use std::path::Path;

/// The hostile part of every string: a script that marks the page if it ever runs, and
/// everything that could end the data element, a comment, an attribute or a line. No `/`, so
/// that it can also be a directory name.
const HOSTILE: &str =
    "<!--<script> <img src=x onerror=\"document.body.setAttribute('data-pwned','1')\"> \
<script>document.body.setAttribute('data-pwned','2')</script> ]]> <![CDATA[ 'single' \"double\" \
a b c &amp; &lt; \\u003c";

/// The `</script>` that only a file's text (not a directory name) can hold.
const CLOSES: &str = "</script><script>document.body.setAttribute('data-pwned','3')</script>";

/// A task title as a suite accepts it (at most 200 visible characters, no control, line
/// separator or invisible character: `isotrack_league` refuses those in titles), still carrying
/// the markup of [`HOSTILE`] and [`CLOSES`].
fn hostile_title() -> String {
    "title <!--<script> <img src=x onerror=\"document.body.setAttribute('data-pwned','1')\"> ]]> \
'single' &amp; </script><script>document.body.setAttribute('data-pwned','3')</script>"
        .to_string()
}

/// A field's hostile string: a tag naming the field, then the hostile text.
fn hostile(tag: &str) -> String {
    format!("{tag} {HOSTILE} {CLOSES}")
}

/// How the browser serialises a text node holding `s` (`--dump-dom`).
fn as_text(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// A TOML string literal of `s`.
fn toml_str(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// The circular field of the paper, 20 s, with a hostile name and units.
fn hostile_scenario(dir: &Path) -> std::path::PathBuf {
    let text = format!(
        r#"name = {name}
[field]
kind = "radial_exp"
units = {units}
[initial]
x_m = 10.0
y_m = 0.0
heading_rad = -1.5707963267948966
[controller]
level = 10.0
[sim]
duration_s = 20.0
"#,
        name = toml_str(&hostile("scenario-name")),
        units = toml_str(&hostile("units")),
    );
    let p = dir.join("hostile.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// Loads `page`; checks that its script finished, logged no error, ran no injected script,
/// and shows every string of `shown` as text. Returns the DOM.
fn check_page(browser: &str, page: &Path, profile: &Path, ready: &str, shown: &[String]) -> String {
    let (dom, log) = load(browser, page, profile, &["--dump-dom"]);
    assert!(
        dom.contains("data-ready=\"1\"") && dom.contains(ready),
        "{}: the page's script did not finish (stuck at loading?): {log}",
        page.display()
    );
    assert_no_script_error(&log);
    assert!(
        !dom.contains("data-pwned=\""),
        "{}: an injected script ran",
        page.display()
    );
    for s in shown {
        assert!(
            dom.contains(&as_text(s)),
            "{}: {s:?} is not shown as text",
            page.display()
        );
    }
    dom
}

/// omega = 0.5 (s - s_d), clipped by the benchmark: a user's controller with a hostile name.
struct Proportional(f64);
impl IsolineController for Proportional {
    fn update(&mut self, m: &Measurement) -> f64 {
        0.5 * (m.value - self.0)
    }
    fn reset(&mut self) {}
}

#[test]
fn benchmark_page_survives_hostile_strings() {
    let Some(browser) = chromium() else { return };
    let d = tempfile::tempdir().unwrap();
    let scenario = hostile_scenario(d.path());
    let suite_text = format!(
        r#"name = {name}
version = 1
controllers = ["pi_isoline"]
tuning_seeds = [11]
scoring_seeds = [1]

[[task]]
id = "t1"
title = {title}
scenario = {scenario}
length_m = 6.93
"#,
        name = toml_str(&hostile("suite")),
        title = toml_str(&hostile_title()),
        scenario = toml_str(&scenario.display().to_string()),
    );
    let suite = isotrack_league::Suite::parse(&suite_text, "hostile-suite.toml", d.path()).unwrap();
    let mut reg = isotrack_league::Registry::builtin();
    // A controller's name is a leaderboard row: the registry refuses `|`, U+2028/9 and names
    // over 64 characters (isotrack_league::check_name), so the hostile one is the markup that
    // fits its rules.
    let factory = |s: &isotrack_scenario::Scenario| {
        Box::new(Proportional(s.level())) as Box<dyn IsolineController + Send>
    };
    assert!(reg.register(&hostile("controller"), factory).is_err());
    let controller = "c <!--<script></script><img src=x onerror=a()>'\"]]>".to_string();
    reg.register(&controller, factory).unwrap();
    let result =
        isotrack_league::run_benchmark(&suite, &reg, &Default::default(), &|_, _, _| {}).unwrap();
    let page = d.path().join("index.html");
    std::fs::write(&page, isotrack_league::benchmark_page(&result)).unwrap();
    let dom = check_page(
        &browser,
        &page,
        &d.path().join("p1"),
        "ready: 2 controllers, 1 tasks",
        &[hostile("suite"), hostile_title(), controller.clone()],
    );
    // The controller's name in the leaderboard, its task table and the picture's legend.
    assert!(dom.matches(&as_text(&controller)).count() >= 3);
}

#[test]
fn report_page_survives_hostile_strings() {
    let Some(browser) = chromium() else { return };
    let d = tempfile::tempdir().unwrap();
    let scenario = hostile_scenario(d.path());
    // A line separator in the scenario's name is refused, never shown (the one plain-text rule).
    let separated = d.path().join("separated.toml");
    std::fs::write(&separated, "name = \"a\\u2028b\"\n").unwrap();
    let o = isotrack(&["run", separated.to_str().unwrap(), "-q"]);
    assert_eq!(o.status.code(), Some(65), "{}", stderr(&o));
    assert!(stderr(&o).contains("U+2028"), "{}", stderr(&o));
    let dirs: Vec<std::path::PathBuf> = ["run-a", "run-b"]
        .iter()
        .map(|t| d.path().join(format!("{t} {HOSTILE}")))
        .collect();
    for dir in &dirs {
        let o = isotrack(&[
            "run",
            scenario.to_str().unwrap(),
            "--out",
            dir.to_str().unwrap(),
            "-q",
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
    let page = d.path().join("report.html");
    let o = isotrack(&[
        "report",
        dirs[0].to_str().unwrap(),
        dirs[1].to_str().unwrap(),
        "--out",
        page.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let names: Vec<String> = dirs
        .iter()
        .map(|p| p.file_name().unwrap().to_str().unwrap().to_string())
        .collect();
    check_page(
        &browser,
        &page,
        &d.path().join("p2"),
        "ready: 2 run(s)",
        &[names[0].clone(), names[1].clone(), hostile("units")],
    );
}

/// Issue 30 (att30c-2): a run directory's name with a bidi override (U+202E), a line
/// separator and an escape was escaped in the `<title>`/`<h1>` but shown raw in the lines the
/// script builds (the run's summary under the title, the legend, `data-run`): the override
/// displayed "completed, steady max |eps| = 1.907" reversed. Every place shows the title's
/// escape, and no raw control reaches the page.
#[test]
fn report_body_shows_a_run_name_as_its_title_does() {
    let Some(browser) = chromium() else { return };
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().join("r\u{202e}evil\u{2028}x\u{1b}[31m");
    let o = isotrack(&[
        "run",
        "--out",
        dir.to_str().unwrap(),
        "--set",
        "sim.duration_s=5",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let page = d.path().join("report.html");
    let o = isotrack(&[
        "report",
        dir.to_str().unwrap(),
        "--out",
        page.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let shown = "r\\u{202e}evil\\u{2028}x\\x1b[31m".to_string();
    let dom = check_page(
        &browser,
        &page,
        &d.path().join("p"),
        "ready: 1 run(s)",
        std::slice::from_ref(&shown),
    );
    for raw in ['\u{202e}', '\u{2028}', '\u{1b}'] {
        assert!(!dom.contains(raw), "{raw:?} raw in the page");
    }
    // The summary line under the title, built by the script, starts with the escaped name.
    assert!(
        dom.contains(&format!("id=\"summary\">{shown}: completed")),
        "the summary line does not show the escaped name"
    );
}

/// Issue 30 item 12: the report of a field that moves (the puff plume, empty at t = 0) shows
/// the frame nearest the slider: 62 s in 32 frames is one every 2 s, so the slider at 0.4 of
/// the run (24.8 s) shows the frame of 24 s (frame 12 of 0..31), and at 0 the frame of 0 s.
#[test]
fn report_of_a_moving_field_follows_the_slider() {
    let Some(browser) = chromium() else { return };
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("puff");
    let scen = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/puff-plume-edge.toml");
    let o = isotrack(&[
        "run",
        scen.to_str().unwrap(),
        "--set",
        "sim.duration_s=62",
        "--out",
        run.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let page = d.path().join("report.html");
    let o = isotrack(&[
        "report",
        run.to_str().unwrap(),
        "--out",
        page.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let html = std::fs::read_to_string(&page).unwrap();
    let dom = check_page(
        &browser,
        &page,
        &d.path().join("p3"),
        "ready: 1 run(s)",
        &[],
    );
    assert!(
        dom.contains("at t = 0.0 s, the frame nearest the cursor (32 frames"),
        "{dom}"
    );
    // Move the slider as a user would (an input event), after the page's scripts ran.
    let moved = d.path().join("moved.html");
    let set = r#"<script>const s = document.getElementById("time"); s.value = "400"; s.dispatchEvent(new Event("input"));</script></body>"#;
    std::fs::write(&moved, html.replacen("</body>", set, 1)).unwrap();
    let dom = check_page(
        &browser,
        &moved,
        &d.path().join("p4"),
        "ready: 1 run(s)",
        &[],
    );
    assert!(
        dom.contains("at t = 24.0 s, the frame nearest the cursor"),
        "{dom}"
    );
}
