//! `isotrack report`: runs as one interactive page.

use crate::{escape, page, script_json};
use isotrack_core::{ScalarField, Vec2};
use isotrack_fields::isoline::IsolineSegments;
use isotrack_plot::{FieldPicture, PlotError, RunData};
use isotrack_scenario::Scenario;
use serde::Serialize;
use std::path::Path;

/// Why a report cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A run directory or file is missing or unreadable.
    #[error("{0}")]
    Input(String),
    /// A file's content is malformed.
    #[error("{0}")]
    Data(String),
}

/// Points per run kept in a page (a longer trace is thinned evenly; the last row is kept).
pub const MAX_POINTS: usize = 5000;

/// Samples per side of the heat map of a field that does not move.
const GRID: usize = 120;

/// Frames of a field that moves, evenly over the run (the first at t = 0, the last at its end).
pub const FRAMES: usize = 32;

/// Samples per side of each frame of a field that moves.
pub const FRAME_GRID: usize = 80;

/// Quantisation of a frame's values: 0 = no value, `1..=QMAX` over the frames' common range.
const QMAX: f64 = 65534.0;

#[derive(Serialize)]
struct RunJson {
    name: String,
    outcome: String,
    summary: serde_json::Value,
    t: Vec<f64>,
    x: Vec<f64>,
    y: Vec<f64>,
    s: Vec<Option<f64>>,
    s_measured: Vec<Option<f64>>,
    error: Vec<Option<f64>>,
    omega: Vec<f64>,
}

#[derive(Serialize)]
struct ReportJson {
    runs: Vec<RunJson>,
    /// The field at t = 0 (for a field that moves: only its square and lattice, the values
    /// and isolines are in `frames`).
    picture: Option<FieldPicture>,
    frames: Option<FramesJson>,
    units: String,
    level: f64,
}

/// A field that moves, at [`FRAMES`] times on the picture's lattice, compactly: each frame's
/// values as little-endian `u16`, base64 (`0` no value, `q` in `1..=65535` the value
/// `lo + (q - 1) / 65534 (hi - lo)`, one range for every frame so that colours compare), and
/// its isoline `s_d` as segments `[x0, y0, x1, y1]` in `u16` (`0..=65535` over the square's
/// `bounds_m`), base64.
#[derive(Serialize)]
struct FramesJson {
    t_s: Vec<f64>,
    range: [f64; 2],
    values: Vec<String>,
    isolines: Vec<String>,
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// The report page of run directories (as written by `isotrack run --out`, `compare --out`):
/// the first run's field as a heat map with the target isoline (at t = 0; a field that moves
/// at [`FRAMES`] times over the run on [`FRAME_GRID`]² samples, the frame nearest the slider
/// shown), every run's path, a time slider with play/pause moving each vehicle along its path,
/// and the error, measurement and turn-rate plots sharing the slider's cursor; hovering shows
/// values with units.
pub fn report_page(dirs: &[&Path]) -> Result<String, ReportError> {
    report_page_with_notes(dirs).map(|(page, _)| page)
}

/// [`report_page`] and the notes a command shows beside it (runs with data files but no
/// recorded data-file digests: `isotrack_plot::unrecorded_data_files_note`).
pub fn report_page_with_notes(dirs: &[&Path]) -> Result<(String, Vec<String>), ReportError> {
    let data = load_runs(dirs)?;
    // The page draws the first run's field under every path: runs over different fields (or
    // isolines) are refused, naming both.
    isotrack_plot::same_field(&data).map_err(|e| ReportError::Data(e.to_string()))?;
    let notes: Vec<String> = isotrack_plot::unrecorded_data_files_note(&data)
        .into_iter()
        .collect();
    let runs: Vec<RunJson> = data.iter().map(run_json).collect();
    let first = data
        .first()
        .ok_or_else(|| ReportError::Input("no run directory given".into()))?;
    let scenario = &first.scenario;
    let (picture, frames) = field_json(scenario, &runs);
    let units = scenario
        .file()
        .field
        .units
        .clone()
        .unwrap_or_else(|| "field units".into());
    let title = format!("isotrack report: {}", named_runs(&runs));
    let body = page_body(&title);
    let json = ReportJson {
        level: scenario.level(),
        runs,
        picture,
        frames,
        units,
    };
    Ok((page(&title, &body, &script_json(&json), REPORT_JS), notes))
}

/// The most runs the page names one by one (in its title; its script's summary line, legend
/// and tooltips likewise): as many as its colours, past which they repeat.
const NAMED_RUNS: usize = 10;

/// The runs' names joined for the title: every name when they are at most [`NAMED_RUNS`],
/// else the first `NAMED_RUNS - 1` and "and K more" (mem45: a team of 10 000 vehicles was
/// titled with every vehicle's name).
fn named_runs(runs: &[RunJson]) -> String {
    let shown = if runs.len() <= NAMED_RUNS {
        runs.len()
    } else {
        NAMED_RUNS - 1
    };
    let mut names: Vec<String> = runs[..shown].iter().map(|r| r.name.clone()).collect();
    if shown < runs.len() {
        names.push(format!("and {} more", runs.len() - shown));
    }
    names.join(", ")
}

/// The runs of the run directories `dirs`, in order: a team's run is its vehicles, each shown
/// as a run (issue 32).
fn load_runs(dirs: &[&Path]) -> Result<Vec<RunData>, ReportError> {
    let mut data: Vec<RunData> = vec![];
    for d in dirs {
        // A team's run is its vehicles, named `DIR vehicle I` among several runs (att32d-7).
        let r = RunData::load_team_named(d, dirs.len() > 1).map_err(|e| match e {
            PlotError::Input(m) => ReportError::Input(m),
            other => ReportError::Data(other.to_string()),
        })?;
        data.extend(r);
    }
    Ok(data)
}

/// One run as the page's script reads it: its name and outcome as shown, its summary, and its
/// trace thinned evenly to at most [`MAX_POINTS`] rows (the last row kept), values that are not
/// finite as `null`.
fn run_json(r: &RunData) -> RunJson {
    let n = r.trace.len();
    let every = n.div_ceil(MAX_POINTS).max(1);
    let keep: Vec<&isotrack_sim::TraceRow> = r
        .trace
        .iter()
        .enumerate()
        .filter(|(i, _)| i.is_multiple_of(every) || *i + 1 == n)
        .map(|(_, row)| row)
        .collect();
    RunJson {
        // The name as the title shows it (every character the plain-text rule refuses as
        // its escape, `\u{202e}`): the script builds the summary line, the legend and
        // `data-run` from it, where a raw U+202E reversed the run's numbers (att30c-2).
        name: isotrack_core::numtext::Escaped(&r.name).to_string(),
        outcome: shown_outcome(r.summary.outcome()).to_string(),
        // As a JSON value (its keys sorted), the page's data as before.
        summary: serde_json::to_value(&r.summary).unwrap_or_default(),
        t: keep.iter().map(|k| k.t_s).collect(),
        x: keep.iter().map(|k| k.x_m).collect(),
        y: keep.iter().map(|k| k.y_m).collect(),
        s: keep.iter().map(|k| finite(k.s)).collect(),
        s_measured: keep.iter().map(|k| k.s_measured.and_then(finite)).collect(),
        error: keep.iter().map(|k| finite(k.error)).collect(),
        omega: keep.iter().map(|k| k.omega_radps).collect(),
    }
}

/// The field under the paths: a field that does not move as one picture on [`GRID`]² samples;
/// one that moves as its square and lattice (on [`FRAME_GRID`]² samples) with the values and
/// isolines in [`FRAMES`] frames over the longest run.
fn field_json(scenario: &Scenario, runs: &[RunJson]) -> (Option<FieldPicture>, Option<FramesJson>) {
    let t_end = runs
        .iter()
        .filter_map(|r| r.t.last().copied())
        .fold(0.0, f64::max);
    let moving = scenario.is_time_varying();
    let mut picture = picture(scenario, runs, if moving { FRAME_GRID } else { GRID });
    let frames = match &mut picture {
        Some(pic) if moving => {
            let f = frames(scenario, pic, t_end);
            pic.values.clear();
            pic.isoline.clear();
            Some(f)
        }
        _ => None,
    };
    (picture, frames)
}

/// The page's body: the title, the time controls, the map with its legend, the charts and the
/// tooltip (the script fills them).
fn page_body(title: &str) -> String {
    format!(
        r#"<h1>{t}</h1>
<p class="sub" id="summary"></p>
<div class="controls"><button id="play" type="button">Play</button> <input id="time" type="range" min="0" max="1000" value="0" step="1" aria-label="time"> <span id="clock">t = 0 s</span></div>
<div class="task">
<div class="mapbox"><canvas id="map" width="628" height="518" aria-label="paths over the field"></canvas><div class="legend" id="legend"></div><p class="note" id="mapnote"></p></div>
<div class="charts" id="charts"></div>
</div>
<div id="tooltip"></div>
<p class="note" id="status">loading</p>"#,
        t = escape(title)
    )
}

fn picture(scenario: &Scenario, runs: &[RunJson], n: usize) -> Option<FieldPicture> {
    let points = runs
        .iter()
        .flat_map(|r| r.x.iter().zip(&r.y).map(|(x, y)| [*x, *y]));
    FieldPicture::around(scenario, points, n)
}

/// The field on `pic`'s lattice at [`FRAMES`] times from 0 to `t_end_s`, with its isolines.
fn frames(scenario: &Scenario, pic: &FieldPicture, t_end_s: f64) -> FramesJson {
    let n = pic.n;
    let [x0, y0, x1, y1] = pic.bounds_m;
    let h = (x1 - x0) / (n - 1) as f64;
    let t_s: Vec<f64> = (0..FRAMES)
        .map(|k| t_end_s * k as f64 / (FRAMES - 1) as f64)
        .collect();
    let field = scenario.field();
    let samples: Vec<Vec<Option<f64>>> = t_s
        .iter()
        .map(|&t| {
            let mut v = Vec::with_capacity(n * n);
            for j in 0..n {
                for i in 0..n {
                    let p = Vec2::new(x0 + i as f64 * h, y0 + j as f64 * h);
                    v.push(field.value(t, p).filter(|v| v.is_finite()));
                }
            }
            v
        })
        .collect();
    let (lo, hi) = samples
        .iter()
        .flatten()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (0.0, 1.0) };
    let quantise = |v: &Option<f64>| match v {
        Some(v) if hi > lo => 1 + ((v - lo) / (hi - lo) * QMAX).round().clamp(0.0, QMAX) as u16,
        Some(_) => 1,
        None => 0,
    };
    let to_u16 =
        |x: f64, a: f64, b: f64| ((x - a) / (b - a) * 65535.0).round().clamp(0.0, 65535.0) as u16;
    let isolines = samples
        .iter()
        .map(|v| {
            // The sample at lattice point p (p = origin + (i h, j h) exactly).
            let at = |p: Vec2| {
                let i = ((p.x - x0) / h).round() as usize;
                let j = ((p.y - y0) / h).round() as usize;
                v.get(j * n + i).copied().flatten()
            };
            let iso = IsolineSegments::from_samples(Vec2::new(x0, y0), h, n, n, pic.level, at);
            let words = iso.segments().iter().flat_map(|(a, b)| {
                [
                    to_u16(a.x, x0, x1),
                    to_u16(a.y, y0, y1),
                    to_u16(b.x, x0, x1),
                    to_u16(b.y, y0, y1),
                ]
            });
            base64_u16(words)
        })
        .collect();
    FramesJson {
        values: samples
            .iter()
            .map(|v| base64_u16(v.iter().map(quantise)))
            .collect(),
        isolines,
        t_s,
        range: [lo, hi],
    }
}

/// `u16` words, little-endian, as base64.
fn base64_u16(words: impl Iterator<Item = u16>) -> String {
    use base64::Engine;
    let bytes: Vec<u8> = words.flat_map(u16::to_le_bytes).collect();
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

const REPORT_JS: &str = r##"
(function () {
  const D = ISO, runs = D.runs, units = D.units;
  const tEnd = Math.max.apply(null, runs.map(r => r.t.length ? r.t[r.t.length - 1] : 0));
  const tip = document.getElementById("tooltip");
  function showTip(ev, text) {
    tip.style.display = "block"; tip.textContent = text;
    tip.style.left = (ev.clientX + 14) + "px"; tip.style.top = (ev.clientY + 10) + "px";
  }
  function hideTip() { tip.style.display = "none"; }
  // Index of the last sample at or before time t (binary search).
  function indexAt(r, t) {
    let lo = 0, hi = r.t.length - 1;
    if (hi < 0) return -1;
    if (t >= r.t[hi]) return hi;
    while (lo < hi) { const mid = (lo + hi + 1) >> 1; if (r.t[mid] <= t) lo = mid; else hi = mid - 1; }
    return lo;
  }
  // The runs the summary line, the legend and the tooltips name one by one: every run when
  // they are at most as many as the colours (past them the colours repeat), else the first
  // PALETTE.length - 1 and "and K more" (mem45: a team of 10 000 vehicles was listed whole).
  const named = runs.length <= PALETTE.length ? runs : runs.slice(0, PALETTE.length - 1);
  const andMore = runs.length > named.length ? ["and " + (runs.length - named.length) + " more"] : [];
  document.getElementById("summary").textContent = named.map(r =>
    r.name + ": " + r.outcome + ", steady max |eps| = " + fmt(r.summary.steady_state_max_abs_error) +
    " " + units + ", convergence " + (r.summary.convergence_time_s === null ? "never" : fmt(r.summary.convergence_time_s, 1) + " s")).concat(andMore).join("; ");
  // The map: the field at t = 0, or for a field that moves the frame nearest the cursor.
  const map = document.getElementById("map"), mctx = map.getContext("2d", { willReadFrequently: true });
  const mapnote = document.getElementById("mapnote");
  const frames = D.frames;
  let pic = D.picture, toPx = null, base = null, shown = -1;
  // Little-endian u16 words from base64.
  function words(b64) {
    const s = atob(b64), out = new Uint16Array(s.length >> 1);
    for (let k = 0; k < out.length; k++) out[k] = s.charCodeAt(2 * k) | (s.charCodeAt(2 * k + 1) << 8);
    return out;
  }
  const framePics = [];
  function framePic(k) {
    if (framePics[k]) return framePics[k];
    const [lo, hi] = frames.range, [x0, y0, x1, y1] = D.picture.bounds_m;
    const values = Array.from(words(frames.values[k]), q => q === 0 ? null : lo + (q - 1) / 65534 * (hi - lo));
    const w = words(frames.isolines[k]), isoline = [];
    const X = q => x0 + q / 65535 * (x1 - x0), Y = q => y0 + q / 65535 * (y1 - y0);
    for (let m = 0; m + 3 < w.length; m += 4) isoline.push([X(w[m]), Y(w[m + 1]), X(w[m + 2]), Y(w[m + 3])]);
    framePics[k] = { bounds_m: D.picture.bounds_m, n: D.picture.n, values: values, isoline: isoline, range: frames.range };
    return framePics[k];
  }
  const width = pic ? fmt(pic.bounds_m[2] - pic.bounds_m[0], 1) + " m" : "";
  function showField(t) {
    if (!D.picture) return;
    const last = frames ? frames.t_s.length - 1 : 0, tLast = frames ? frames.t_s[last] : 0;
    const k = tLast > 0 ? Math.min(last, Math.max(0, Math.round(t / tLast * last))) : 0;
    if (k === shown) return;
    shown = k;
    pic = frames ? framePic(k) : D.picture;
    toPx = drawField(map, pic, { units: units });
    base = mctx.getImageData(0, 0, map.width, map.height);
    mapnote.textContent = frames
      ? "field and isoline s_d = " + fmt(D.level) + " " + units + " (dashed) at t = " + fmt(frames.t_s[k], 1) + " s, the frame nearest the cursor (" +
        frames.t_s.length + " frames over the run, " + pic.n + " x " + pic.n + " samples; colours from " + fmt(frames.range[0]) + " to " + fmt(frames.range[1]) + " " + units + "); width " + width
      : "isoline s_d = " + fmt(D.level) + " " + units + " dashed (field at t = 0); width " + width;
  }
  if (!pic) mapnote.textContent = "no path to draw";
  const legend = document.getElementById("legend");
  named.forEach((r, i) => {
    const item = el("span", { "data-run": r.name }, r.name + " (" + r.outcome + ")");
    const sw = el("span", { class: "swatch" }); sw.style.background = colour(i); item.prepend(sw);
    legend.appendChild(item);
  });
  andMore.forEach(m => legend.appendChild(el("span", {}, m)));
  function drawMap(t) {
    if (!pic) return;
    showField(t);
    mctx.putImageData(base, 0, 0);
    // Paths and vehicles inside the map's square only (not over its axes and colour bar).
    const [al, at, aw, ah] = toPx.area;
    mctx.save(); mctx.beginPath(); mctx.rect(al, at, aw, ah); mctx.clip();
    runs.forEach((r, i) => {
      drawPath(mctx, toPx, r.x, r.y, colour(i), 1.5);
      const k = indexAt(r, t);
      if (k >= 0 && isFinite(r.x[k])) {
        const p = toPx(r.x[k], r.y[k]);
        mctx.fillStyle = colour(i); mctx.strokeStyle = "#000"; mctx.lineWidth = 1.5;
        mctx.beginPath(); mctx.arc(p[0], p[1], 6, 0, 2 * Math.PI); mctx.fill(); mctx.stroke();
      }
    });
    mctx.restore();
  }
  map.addEventListener("mousemove", ev => {
    if (!pic) return;
    const rect = map.getBoundingClientRect(), [al, at, aw, ah] = toPx.area;
    // Canvas pixels under the pointer (the canvas may be scaled by the page), then the map's
    // square.
    const cx = (ev.clientX - rect.left) * map.width / rect.width, cy = (ev.clientY - rect.top) * map.height / rect.height;
    const u = (cx - al) / aw, v = (cy - at) / ah;
    if (!(u >= 0 && u <= 1 && v >= 0 && v <= 1)) { hideTip(); return; }
    const [x0, y0, x1, y1] = pic.bounds_m;
    const x = x0 + u * (x1 - x0), y = y1 - v * (y1 - y0);
    const i = Math.round(u * (pic.n - 1)), j = Math.round((1 - v) * (pic.n - 1));
    const val = (i >= 0 && j >= 0 && i < pic.n && j < pic.n) ? pic.values[j * pic.n + i] : null;
    showTip(ev, "x = " + fmt(x, 1) + " m, y = " + fmt(y, 1) + " m, field = " + (val === null ? "no value" : fmt(val) + " " + units));
  });
  map.addEventListener("mouseleave", hideTip);
  // The time series: error, measurement, turn rate.
  const charts = document.getElementById("charts");
  const series = [
    { key: "error", label: "error s - s_d", unit: units },
    { key: "s_measured", label: "measured s", unit: units, also: "s" },
    { key: "omega", label: "turn rate omega", unit: "rad/s" },
  ];
  const W = 620, H = 160, L = 62, Rm = 10, T = 18, B = 24;
  const SVGNS = "http://www.w3.org/2000/svg";
  function svgEl(tag, attrs) { const e = document.createElementNS(SVGNS, tag); for (const k in attrs) e.setAttribute(k, attrs[k]); return e; }
  const cursors = [];
  let current = 0;
  for (const sdef of series) {
    let lo = Infinity, hi = -Infinity;
    for (const r of runs) for (const key of [sdef.key, sdef.also]) {
      if (!key) continue;
      for (const v of r[key]) if (v !== null && isFinite(v)) { if (v < lo) lo = v; if (v > hi) hi = v; }
    }
    if (!(lo < hi)) { lo = (isFinite(lo) ? lo : 0) - 1; hi = lo + 2; }
    const sx = t => L + (tEnd > 0 ? t / tEnd : 0) * (W - L - Rm);
    const sy = v => T + (1 - (v - lo) / (hi - lo)) * (H - T - B);
    const svg = svgEl("svg", { width: W, height: H, "data-series": sdef.key, role: "img", "aria-label": sdef.label });
    svg.appendChild(svgEl("rect", { x: L, y: T, width: W - L - Rm, height: H - T - B, fill: "#fafafa", stroke: "#bbb" }));
    const title = svgEl("text", { x: L, y: 13, "font-size": 12 }); title.textContent = sdef.label + " (" + sdef.unit + ")"; svg.appendChild(title);
    for (const v of [lo, hi]) { const tx = svgEl("text", { x: L - 4, y: sy(v) + 4, "font-size": 10, "text-anchor": "end" }); tx.textContent = fmt(v, 2); svg.appendChild(tx); }
    for (const tt of [0, tEnd]) { const tx = svgEl("text", { x: sx(tt), y: H - 8, "font-size": 10, "text-anchor": tt === 0 ? "start" : "end" }); tx.textContent = fmt(tt, 0) + " s"; svg.appendChild(tx); }
    runs.forEach((r, i) => {
      for (const key of [sdef.also, sdef.key]) {
        if (!key) continue;
        let d = "", pen = false;
        for (let k = 0; k < r.t.length; k++) {
          const v = r[key][k];
          if (v === null || !isFinite(v)) { pen = false; continue; }
          d += (pen ? "L" : "M") + sx(r.t[k]).toFixed(1) + " " + sy(v).toFixed(1);
          pen = true;
        }
        svg.appendChild(svgEl("path", { d: d, fill: "none", stroke: colour(i), "stroke-width": key === sdef.also ? 1 : 1.4, "stroke-dasharray": key === sdef.also ? "3 2" : "" }));
      }
    });
    const cur = svgEl("line", { x1: L, x2: L, y1: T, y2: H - B, stroke: "#000", "stroke-width": 1 });
    svg.appendChild(cur); cursors.push([cur, sx]);
    svg.addEventListener("mousemove", ev => {
      const rect = svg.getBoundingClientRect();
      const t = Math.min(tEnd, Math.max(0, (ev.clientX - rect.left - L) / (W - L - Rm) * tEnd));
      setTime(t);
      showTip(ev, "t = " + fmt(t, 2) + " s: " + named.map(r => {
        const k = indexAt(r, t), v = k >= 0 ? r[sdef.key][k] : null;
        return r.name + " " + sdef.label + " = " + (v === null ? "n/a" : fmt(v)) + " " + sdef.unit;
      }).concat(andMore).join("; "));
    });
    svg.addEventListener("mouseleave", hideTip);
    charts.appendChild(svg);
  }
  const slider = document.getElementById("time"), clock = document.getElementById("clock");
  function setTime(t) {
    current = t;
    slider.value = String(tEnd > 0 ? Math.round(t / tEnd * 1000) : 0);
    clock.textContent = "t = " + fmt(t, 1) + " s";
    for (const [c, sx] of cursors) { const x = sx(t); c.setAttribute("x1", x); c.setAttribute("x2", x); }
    drawMap(t);
  }
  slider.addEventListener("input", () => setTime(Number(slider.value) / 1000 * tEnd));
  const play = document.getElementById("play");
  let timer = null;
  play.addEventListener("click", () => {
    if (timer) { clearInterval(timer); timer = null; play.textContent = "Play"; return; }
    if (current >= tEnd) current = 0;
    play.textContent = "Pause";
    timer = setInterval(() => {
      const next = Math.min(tEnd, current + tEnd / 400);
      setTime(next);
      if (next >= tEnd) { clearInterval(timer); timer = null; play.textContent = "Play"; }
    }, 40);
  });
  setTime(0);
  document.getElementById("status").textContent = "ready: " + runs.length + " run(s)";
  document.body.setAttribute("data-ready", "1");
})();
"##;

/// A summary's `outcome` as the page shows it: an outcome isotrack writes is a short snake_case
/// word (`completed`, `left_field`, `interrupted`, a flight's `link_lost`, ...); anything else
/// (a doctored `summary.json`'s `<!--<script>` + U+202E) is shown as `unknown`.
fn shown_outcome(outcome: &str) -> &str {
    let word = !outcome.is_empty()
        && outcome.len() <= 32
        && outcome.bytes().all(|b| b.is_ascii_lowercase() || b == b'_');
    if word {
        outcome
    } else {
        "unknown"
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use base64::Engine;

    /// Issue 30 (att30b item 13): a doctored `summary.json`'s `outcome` (markup and a U+202E)
    /// is shown as `unknown`; the outcomes isotrack writes are shown as they are.
    #[test]
    fn an_unknown_outcome_is_shown_as_unknown() {
        for o in [
            "completed",
            "left_field",
            "diverged",
            "interrupted",
            "link_lost",
        ] {
            assert_eq!(shown_outcome(o), o);
        }
        for o in [
            "<!--<script>\u{202e}",
            "",
            "Completed",
            "a b",
            &"x".repeat(33),
        ] {
            assert_eq!(shown_outcome(o), "unknown", "{o:?}");
        }
    }

    fn words(b64: &str) -> Vec<u16> {
        base64::engine::general_purpose::STANDARD
            .decode(b64)
            .unwrap()
            .chunks(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]))
            .collect()
    }

    /// A field that moves: the paper's circular field drifting at (0.2, 0.1) m/s. Every frame's
    /// decoded values are `20 exp(-0.1 |p - v t|)` at its time to the 16-bit quantum, and every
    /// isoline end point lies on the circle of radius `10 ln 2` round the moved centre (to
    /// the lattice's chord error and the 16-bit position quantum).
    #[test]
    fn frames_of_a_drifting_field_are_the_field_at_their_times() {
        let sc =
            isotrack_scenario::parse_scenario("", "<test>", &["field.drift_mps=[0.2, 0.1]".into()])
                .unwrap();
        assert!(sc.is_time_varying());
        let pic = FieldPicture::around(&sc, [[-15.0, -15.0], [25.0, 25.0]], 41).unwrap();
        let f = frames(&sc, &pic, 100.0);
        assert_eq!(f.t_s.len(), FRAMES);
        assert_eq!((f.t_s[0], f.t_s[FRAMES - 1]), (0.0, 100.0));
        let [x0, y0, x1, y1] = pic.bounds_m;
        let h = (x1 - x0) / 40.0;
        let [lo, hi] = f.range;
        let drift = Vec2::new(0.2, 0.1);
        for (k, &t) in f.t_s.iter().enumerate() {
            let q = words(&f.values[k]);
            assert_eq!(q.len(), 41 * 41);
            for j in 0..41 {
                for i in 0..41 {
                    let p = Vec2::new(x0 + i as f64 * h, y0 + j as f64 * h);
                    let want = 20.0 * (-0.1 * (p - drift * t).norm()).exp();
                    let got = lo + (q[j * 41 + i] as f64 - 1.0) / 65534.0 * (hi - lo);
                    assert!(
                        (got - want).abs() <= 0.5 * (hi - lo) / 65534.0 + 1e-12,
                        "{t} {p:?}"
                    );
                }
            }
            let w = words(&f.isolines[k]);
            assert!(
                w.len() >= 4 * 20 && w.len().is_multiple_of(4),
                "{t}: {}",
                w.len()
            );
            let r = 10.0 * std::f64::consts::LN_2;
            for c in w.chunks(2) {
                let p = Vec2::new(
                    x0 + c[0] as f64 / 65535.0 * (x1 - x0),
                    y0 + c[1] as f64 / 65535.0 * (y1 - y0),
                );
                let d = (p - drift * t).norm() - r;
                assert!(d.abs() < 0.05, "{t}: {p:?} is {d} m off the circle");
            }
        }
        assert!((hi - 20.0).abs() < 1.0 && lo > 0.0, "{lo} {hi}");
    }
}
