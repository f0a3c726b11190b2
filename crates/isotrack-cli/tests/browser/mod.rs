//! Headless Chromium for the tests of the HTML pages: find it, load a page (its DOM after the
//! scripts ran, or a screenshot), check the browser's log and a screenshot.
#![allow(dead_code)] // each test file uses its own subset

use std::path::Path;
use std::process::Command;

/// Headless Chromium, if installed (`.ci/run` installs it and sets ISOTRACK_REQUIRE_BROWSER=1,
/// so that CI fails rather than skips).
pub fn chromium() -> Option<String> {
    for c in ["chromium", "chromium-browser", "google-chrome"] {
        if Command::new(c)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
        {
            return Some(c.to_string());
        }
    }
    assert!(
        std::env::var_os("ISOTRACK_REQUIRE_BROWSER").is_none(),
        "ISOTRACK_REQUIRE_BROWSER is set but no chromium is installed"
    );
    eprintln!("skipped: no chromium on PATH");
    None
}

/// Loads a page headless: (the DOM after its scripts ran, the browser's log).
pub fn load(browser: &str, page: &Path, profile: &Path, extra: &[&str]) -> (String, String) {
    let url = format!("file://{}", page.canonicalize().unwrap().display());
    let o = Command::new("timeout")
        .arg("120")
        .arg(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--enable-logging=stderr",
            "--v=0",
            "--virtual-time-budget=5000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(&url)
        .output()
        .unwrap();
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// A screenshot that is not blank: many distinct colours (the heat map), not all white.
pub fn assert_not_blank(png: &Path) {
    let img = image::open(png).unwrap().to_rgb8();
    let mut colours = std::collections::HashSet::new();
    for p in img.pixels() {
        colours.insert(p.0);
    }
    assert!(
        colours.len() > 200,
        "{} colours in {}",
        colours.len(),
        png.display()
    );
}

pub fn assert_no_script_error(log: &str) {
    for line in log.lines() {
        assert!(
            !line.contains("Uncaught") && !line.contains(":CONSOLE"),
            "browser console: {line}"
        );
    }
}
