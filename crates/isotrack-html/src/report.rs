//! `isotrack report`: runs as one interactive page.

use crate::{escape, page, script_json};
use isotrack_plot::{PlotError, RunData};
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

/// Samples per side of the heat map.
const GRID: usize = 120;

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
    picture: Option<isotrack_bench::run::FieldPicture>,
    units: String,
    level: f64,
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// The report page of run directories (as written by `isotrack run --out`, `compare --out`):
/// the first run's field at t = 0 as a heat map with the target isoline, every run's path, a
/// time slider with play/pause moving each vehicle along its path, and the error, measurement
/// and turn-rate plots sharing the slider's cursor; hovering shows values with units.
pub fn report_page(dirs: &[&Path]) -> Result<String, ReportError> {
    let mut runs = vec![];
    let mut data: Vec<RunData> = vec![];
    for d in dirs {
        let r = RunData::load(d).map_err(|e| match e {
            PlotError::Input(m) => ReportError::Input(m),
            other => ReportError::Data(other.to_string()),
        })?;
        data.push(r);
    }
    for r in &data {
        let n = r.trace.len();
        let every = n.div_ceil(MAX_POINTS).max(1);
        let keep: Vec<&isotrack_sim::TraceRow> = r
            .trace
            .iter()
            .enumerate()
            .filter(|(i, _)| i.is_multiple_of(every) || *i + 1 == n)
            .map(|(_, row)| row)
            .collect();
        runs.push(RunJson {
            name: r.name.clone(),
            outcome: r.summary["outcome"].as_str().unwrap_or("").to_string(),
            summary: r.summary.clone(),
            t: keep.iter().map(|k| k.t_s).collect(),
            x: keep.iter().map(|k| k.x_m).collect(),
            y: keep.iter().map(|k| k.y_m).collect(),
            s: keep.iter().map(|k| finite(k.s)).collect(),
            s_measured: keep.iter().map(|k| k.s_measured.and_then(finite)).collect(),
            error: keep.iter().map(|k| finite(k.error)).collect(),
            omega: keep.iter().map(|k| k.omega_radps).collect(),
        });
    }
    let first = data
        .first()
        .ok_or_else(|| ReportError::Input("no run directory given".into()))?;
    let scenario = &first.scenario;
    let picture = picture(scenario, &runs);
    let units = scenario
        .file()
        .field
        .units
        .clone()
        .unwrap_or_else(|| "field units".into());
    let title = format!(
        "isotrack report: {}",
        runs.iter()
            .map(|r| r.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    );
    let body = format!(
        r#"<h1>{t}</h1>
<p class="sub" id="summary"></p>
<div class="controls"><button id="play" type="button">Play</button> <input id="time" type="range" min="0" max="1000" value="0" step="1" aria-label="time"> <span id="clock">t = 0 s</span></div>
<div class="task">
<div><canvas id="map" width="520" height="520" aria-label="paths over the field"></canvas><div class="legend" id="legend"></div><p class="note" id="mapnote"></p></div>
<div class="charts" id="charts"></div>
</div>
<div id="tooltip"></div>
<p class="note" id="status">loading</p>"#,
        t = escape(&title)
    );
    let json = ReportJson {
        level: scenario.level(),
        runs,
        picture,
        units,
    };
    Ok(page(&title, &body, &script_json(&json), REPORT_JS))
}

fn picture(
    scenario: &isotrack_scenario::Scenario,
    runs: &[RunJson],
) -> Option<isotrack_bench::run::FieldPicture> {
    let points = runs
        .iter()
        .flat_map(|r| r.x.iter().zip(&r.y).map(|(x, y)| [*x, *y]));
    isotrack_bench::run::FieldPicture::around(scenario, points, GRID)
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
  document.getElementById("summary").textContent = runs.map(r =>
    r.name + ": " + r.outcome + ", steady max |eps| = " + fmt(r.summary.steady_state_max_abs_error) +
    " " + units + ", convergence " + (r.summary.convergence_time_s === null ? "never" : fmt(r.summary.convergence_time_s, 1) + " s")).join("; ");
  // The map.
  const map = document.getElementById("map"), mctx = map.getContext("2d");
  const pic = D.picture;
  let toPx = null, base = null;
  if (pic) {
    toPx = drawField(map, pic);
    base = mctx.getImageData(0, 0, map.width, map.height);
    document.getElementById("mapnote").textContent = "isoline s_d = " + fmt(D.level) + " " + units + " dashed (field at t = 0); width " + fmt(pic.bounds_m[2] - pic.bounds_m[0], 1) + " m";
  } else {
    document.getElementById("mapnote").textContent = "no path to draw";
  }
  const legend = document.getElementById("legend");
  runs.forEach((r, i) => {
    const item = el("span", { "data-run": r.name }, r.name + " (" + r.outcome + ")");
    const sw = el("span", { class: "swatch" }); sw.style.background = colour(i); item.prepend(sw);
    legend.appendChild(item);
  });
  function drawMap(t) {
    if (!pic) return;
    mctx.putImageData(base, 0, 0);
    runs.forEach((r, i) => {
      drawPath(mctx, toPx, r.x, r.y, colour(i), 1.5);
      const k = indexAt(r, t);
      if (k >= 0 && isFinite(r.x[k])) {
        const p = toPx(r.x[k], r.y[k]);
        mctx.fillStyle = colour(i); mctx.strokeStyle = "#000"; mctx.lineWidth = 1.5;
        mctx.beginPath(); mctx.arc(p[0], p[1], 6, 0, 2 * Math.PI); mctx.fill(); mctx.stroke();
      }
    });
  }
  map.addEventListener("mousemove", ev => {
    if (!pic) return;
    const rect = map.getBoundingClientRect();
    const u = (ev.clientX - rect.left) / rect.width, v = (ev.clientY - rect.top) / rect.height;
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
      showTip(ev, "t = " + fmt(t, 2) + " s: " + runs.map(r => {
        const k = indexAt(r, t), v = k >= 0 ? r[sdef.key][k] : null;
        return r.name + " " + sdef.label + " = " + (v === null ? "n/a" : fmt(v)) + " " + sdef.unit;
      }).join("; "));
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
