//! # isotrack-html
//!
//! Self-contained HTML pages: the data as JSON in the page, inline CSS and JavaScript, no
//! network and no CDN, so a page works from `file://` and can be mailed or archived.
//!
//! * [`page`], [`escape`], [`script_json`]: the page shell and the escaping every page goes
//!   through (the benchmark's `index.html` is built on them in `isotrack-league`).
//! * [`report_page`]: one or more runs (field heat map with the target isoline, the paths, a
//!   play/pause time slider, error / measurement / turn-rate plots on the same cursor, hover
//!   values with units).
//!
//! Hand-written: the pages are small and fixed, and a templating or charting library would
//! either fetch scripts from the network or add more code than the pages themselves.
#![deny(missing_docs)]

mod report;

pub use report::{report_page, report_page_with_notes, ReportError};

/// Text escaped for HTML element content and quoted attribute values (`&`, `<`, `>`, `"`, `'`),
/// after every character that is not plain text (the one rule,
/// [`isotrack_core::numtext::is_escaped`]: ESC, U+202E, U+2028, U+200B, ...) is shown as its
/// escape (`\x1b`, `\u{202e}`) as the console shows it: a run directory named
/// `d` + U+202E + `evil` would otherwise render reversed in the page's title and heading.
pub fn escape(s: &str) -> String {
    isotrack_core::numtext::Escaped(s)
        .to_string()
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&#39;")
}

/// JSON safe inside `<script type="application/json">`: every `<`, `>` and `&` is written as
/// `\u003c`, `\u003e`, `\u0026`, U+2028 / U+2029 as `\u2028` / `\u2029`, and the invisible
/// characters ([`isotrack_core::numtext::is_invisible`]: bidi controls, zero-width ones) as
/// `\uXXXX`.
///
/// Escaping only `</` is not enough: `<!--` followed by `<script` puts the HTML parser in the
/// "script data double escaped" state (WHATWG HTML, 13.2.5.20 ff.), where `</script>` no
/// longer closes the element, so the data swallows the page's scripts. With no `<` left in
/// the element's text no tag or comment can start in it. These characters occur in JSON only
/// inside strings, where `\uXXXX` is the same character to `JSON.parse`, so the data is
/// unchanged. (U+2028/9 are line terminators to pre-2019 JavaScript.)
pub fn script_json<T: serde::Serialize>(v: &T) -> String {
    let json = serde_json::to_string(v).unwrap_or_else(|_| "null".into());
    escape_script_json(&json)
}

/// The escaping of [`script_json`] on JSON text.
fn escape_script_json(json: &str) -> String {
    let mut out = String::with_capacity(json.len() + json.len() / 16);
    for c in json.chars() {
        match c {
            '<' => out.push_str("\\u003c"),
            '>' => out.push_str("\\u003e"),
            '&' => out.push_str("\\u0026"),
            '\u{2028}' => out.push_str("\\u2028"),
            '\u{2029}' => out.push_str("\\u2029"),
            // Bidi controls and other invisible characters (U+202E reverses what follows in
            // a view of the page's source): as `\uXXXX` escapes, surrogate pairs above the
            // BMP (issue 30, fix30c).
            // Every character the one plain-text rule refuses (issue 30, att30b item 3).
            c if isotrack_core::numtext::is_not_plain(c) => {
                let mut units = [0u16; 2];
                for u in c.encode_utf16(&mut units) {
                    out.push_str(&format!("\\u{:04x}", u));
                }
            }
            c => out.push(c),
        }
    }
    out
}

/// The page shell: title, CSS, the data (`data_json`, from [`script_json`]), the shared script
/// (`el`, `colour`, `fmt`, `drawField`, `drawPath`, the data as `ISO`), the page's script.
pub fn page(title: &str, body: &str, data_json: &str, script: &str) -> String {
    format!(
        r#"<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta name="generator" content="isotrack {version}">
<title>{title}</title>
<style>{CSS}</style>
</head>
<body>
{body}
<script id="isotrack-data" type="application/json">{data_json}</script>
<script>{COMMON_JS}</script>
<script>{script}</script>
</body>
</html>
"#,
        version = env!("CARGO_PKG_VERSION"),
        title = escape(title),
    )
}

const CSS: &str = r##"
body { font-family: "DejaVu Sans", Arial, sans-serif; margin: 1.5em auto; max-width: 1300px; color: #222; padding: 0 1em; }
h1 { font-size: 1.5em; margin-bottom: 0.2em; } h2 { font-size: 1.2em; margin-top: 1.6em; }
.sub { color: #666; margin-top: 0; }
table { border-collapse: collapse; margin: 0.5em 0; font-size: 0.92em; }
th, td { border: 1px solid #ccc; padding: 3px 8px; text-align: right; }
th { background: #f2f2f2; cursor: pointer; user-select: none; }
td:first-child, th:first-child { text-align: left; }
th.sorted-desc::after { content: " \25BC"; } th.sorted-asc::after { content: " \25B2"; }
.task { display: flex; gap: 1.2em; align-items: flex-start; flex-wrap: wrap; }
canvas { border: 1px solid #bbb; }
.legend span { display: inline-block; margin-right: 1em; font-size: 0.85em; }
.swatch { display: inline-block; width: 12px; height: 12px; margin-right: 4px; vertical-align: middle; }
.controls { margin: 0.6em 0; } .controls input[type=range] { width: 60%; vertical-align: middle; }
#tooltip { position: fixed; pointer-events: none; background: rgba(20,20,20,0.85); color: #fff; padding: 3px 7px; border-radius: 3px; font-size: 0.85em; display: none; z-index: 10; }
.charts svg { display: block; margin-bottom: 6px; }
.note { color: #555; font-size: 0.88em; }
.mapbox { max-width: 632px; }
"##;

/// Shared by both pages: the colour map, the heat map, the colours of controllers.
const COMMON_JS: &str = r##"
"use strict";
const ISO = JSON.parse(document.getElementById("isotrack-data").textContent);
const VIRIDIS = [[68,1,84],[72,40,120],[62,74,137],[49,104,142],[38,130,142],[31,158,137],[53,183,121],[109,205,89],[180,222,44],[253,231,37]];
function viridis(u) {
  if (!isFinite(u)) return [0,0,0];
  u = Math.min(1, Math.max(0, u)) * (VIRIDIS.length - 1);
  const i = Math.min(VIRIDIS.length - 2, Math.floor(u)), f = u - i;
  return [0,1,2].map(k => Math.round(VIRIDIS[i][k] + f * (VIRIDIS[i + 1][k] - VIRIDIS[i][k])));
}
const PALETTE = ["#e41a1c","#ff7f00","#f781bf","#a65628","#984ea3","#4daf4a","#377eb8","#999999","#00bcd4","#000000"];
function colour(i) { return PALETTE[i % PALETTE.length]; }
// The field as a heat map on a canvas: values n x n (row 0 at y_min), bounds [x0,y0,x1,y1],
// coloured over pic.range [lo, hi] if given (else the values' own range), and the isoline
// pic.isoline dashed. With `frame` ({ units }) the map is drawn inside margins with axes in
// metres and a colour bar in the field's units (the level marked on it); without, over the
// whole canvas. Returns a function from metres to canvas pixels, its plot area in `.area`
// ([left, top, side] px).
function drawField(canvas, pic, frame) {
  const ctx = canvas.getContext("2d");
  const m = frame ? { l: 64, r: 104, t: 12, b: 46 } : { l: 0, r: 0, t: 0, b: 0 };
  const W = canvas.width - m.l - m.r, H = canvas.height - m.t - m.b;
  const [x0, y0, x1, y1] = pic.bounds_m;
  const toPx = (x, y) => [m.l + (x - x0) / (x1 - x0) * W, m.t + H - (y - y0) / (y1 - y0) * H];
  toPx.area = [m.l, m.t, W, H];
  if (frame) { ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, canvas.width, canvas.height); }
  ctx.fillStyle = "#ddd"; ctx.fillRect(m.l, m.t, W, H);
  let lo = Infinity, hi = -Infinity;
  const vals = pic.values.filter(v => v !== null && isFinite(v));
  if (vals.length > 0) {
    if (pic.range) [lo, hi] = pic.range;
    else for (const v of vals) { if (v < lo) lo = v; if (v > hi) hi = v; }
    const n = pic.n, img = ctx.createImageData(n, n);
    for (let j = 0; j < n; j++) for (let i = 0; i < n; i++) {
      const v = pic.values[j * n + i], o = ((n - 1 - j) * n + i) * 4;
      if (v === null || !isFinite(v)) { img.data[o + 3] = 0; continue; }
      const c = viridis(hi > lo ? (v - lo) / (hi - lo) : 0.5);
      img.data[o] = c[0]; img.data[o + 1] = c[1]; img.data[o + 2] = c[2]; img.data[o + 3] = 255;
    }
    const off = document.createElement("canvas"); off.width = n; off.height = n;
    off.getContext("2d").putImageData(img, 0, 0);
    ctx.imageSmoothingEnabled = true;
    ctx.drawImage(off, m.l, m.t, W, H);
  }
  // The isoline as polylines, so the dash pattern runs along it: stroked segment by segment
  // (each a cell's chord, a few pixels long), every segment restarted the pattern and the
  // line drew solid. A dark line under the white dashes keeps them visible on light colours.
  const lines = isolinePolylines(pic.isoline, x1 - x0);
  for (const [style, width, dash] of [["rgba(0,0,0,0.55)", 3.5, []], ["#ffffff", 2, [7, 5]]]) {
    ctx.strokeStyle = style; ctx.lineWidth = width; ctx.setLineDash(dash);
    ctx.beginPath();
    for (const line of lines) {
      line.forEach((p, k) => { const q = toPx(p[0], p[1]); if (k === 0) ctx.moveTo(q[0], q[1]); else ctx.lineTo(q[0], q[1]); });
    }
    ctx.stroke();
  }
  ctx.setLineDash([]);
  canvas.dataset.isolineLines = String(lines.length);
  if (frame) drawFrame(canvas, ctx, m, W, H, pic, lo, hi, frame.units);
  return toPx;
}
// Segments [x0, y0, x1, y1] joined end to end into polylines ([[x, y], ...]): end points equal
// to 1e-7 of `size` are one point (marching squares put a segment's end on a cell edge,
// shared with the next cell's segment).
function isolinePolylines(segs, size) {
  const q = (size > 0 ? size : 1) * 1e-7;
  const key = (x, y) => Math.round(x / q) + "," + Math.round(y / q);
  const at = new Map();
  segs.forEach((s, i) => {
    for (const k of [key(s[0], s[1]), key(s[2], s[3])]) { if (!at.has(k)) at.set(k, []); at.get(k).push(i); }
  });
  const used = new Uint8Array(segs.length), lines = [];
  // From point p, the next unused segment touching it: its far end (or null).
  function next(p) {
    const list = at.get(key(p[0], p[1])) || [];
    for (const i of list) {
      if (used[i]) continue;
      used[i] = 1;
      const s = segs[i];
      return key(s[0], s[1]) === key(p[0], p[1]) ? [s[2], s[3]] : [s[0], s[1]];
    }
    return null;
  }
  segs.forEach((s, i) => {
    if (used[i]) return;
    used[i] = 1;
    const fwd = [[s[0], s[1]], [s[2], s[3]]];
    for (let p = next(fwd[fwd.length - 1]); p; p = next(p)) fwd.push(p);
    const back = [];
    for (let p = next(fwd[0]); p; p = next(p)) back.push(p);
    lines.push(back.reverse().concat(fwd));
  });
  return lines;
}
// Ticks over [a, b]: multiples of 1, 2 or 5 x 10^k, about `count` of them.
function niceTicks(a, b, count) {
  if (!(b > a)) return { step: 0, ticks: [a] };
  const raw = (b - a) / count, p = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 5, 10].map(f => f * p).find(s => s >= raw * 0.999);
  const ticks = [];
  for (let k = Math.ceil(a / step - 1e-9); k * step <= b + 1e-9 * step; k++) ticks.push(k * step);
  return { step: step, ticks: ticks };
}
// A tick's label: as many decimals as the step needs.
function tickLabel(v, step) {
  const d = Math.max(0, Math.min(8, -Math.floor(Math.log10(step) + 1e-9)));
  const a = Math.abs(step);
  if (a >= 1e5 || a < 1e-4) return v.toExponential(1);
  return (Math.abs(v) < step * 1e-9 ? 0 : v).toFixed(d);
}
// Axes (x and y in metres) round the plot area and a colour bar of [lo, hi] `units` on its
// right, the isoline's level marked on it. Their labels are also written to the canvas's
// data-x-ticks, data-y-ticks, data-colour-ticks and data-colour-label (and its aria-label).
function drawFrame(canvas, ctx, m, W, H, pic, lo, hi, units) {
  const [x0, y0, x1, y1] = pic.bounds_m;
  ctx.strokeStyle = "#444"; ctx.lineWidth = 1; ctx.strokeRect(m.l + 0.5, m.t + 0.5, W - 1, H - 1);
  ctx.fillStyle = "#222"; ctx.font = "11px 'DejaVu Sans', Arial, sans-serif";
  const xt = niceTicks(x0, x1, 5), yt = niceTicks(y0, y1, 5);
  ctx.textAlign = "center"; ctx.textBaseline = "top";
  const xl = xt.ticks.map(v => tickLabel(v, xt.step));
  xt.ticks.forEach((v, k) => {
    const px = m.l + (v - x0) / (x1 - x0) * W;
    ctx.beginPath(); ctx.moveTo(px, m.t + H); ctx.lineTo(px, m.t + H + 5); ctx.stroke();
    ctx.fillText(xl[k], px, m.t + H + 7);
  });
  ctx.fillText("x (m)", m.l + W / 2, m.t + H + 24);
  ctx.textAlign = "right"; ctx.textBaseline = "middle";
  const yl = yt.ticks.map(v => tickLabel(v, yt.step));
  yt.ticks.forEach((v, k) => {
    const py = m.t + H - (v - y0) / (y1 - y0) * H;
    ctx.beginPath(); ctx.moveTo(m.l - 5, py); ctx.lineTo(m.l, py); ctx.stroke();
    ctx.fillText(yl[k], m.l - 7, py);
  });
  ctx.save(); ctx.translate(14, m.t + H / 2); ctx.rotate(-Math.PI / 2);
  ctx.textAlign = "center"; ctx.fillText("y (m)", 0, 0); ctx.restore();
  // The colour bar.
  const bx = m.l + W + 14, bw = 14;
  const label = "field (" + units + ")";
  let cl = [];
  if (hi >= lo && isFinite(lo)) {
    for (let py = 0; py < H; py++) {
      const c = viridis(1 - py / Math.max(1, H - 1));
      ctx.fillStyle = "rgb(" + c[0] + "," + c[1] + "," + c[2] + ")";
      ctx.fillRect(bx, m.t + py, bw, 1);
    }
    ctx.strokeStyle = "#444"; ctx.strokeRect(bx + 0.5, m.t + 0.5, bw - 1, H - 1);
    const ct = hi > lo ? niceTicks(lo, hi, 5) : { step: Math.abs(lo) || 1, ticks: [lo] };
    const at = v => hi > lo ? m.t + H - (v - lo) / (hi - lo) * H : m.t + H / 2;
    ctx.fillStyle = "#222"; ctx.textAlign = "left"; ctx.textBaseline = "middle";
    cl = ct.ticks.map(v => tickLabel(v, ct.step));
    ct.ticks.forEach((v, k) => {
      const py = at(v);
      ctx.beginPath(); ctx.moveTo(bx + bw, py); ctx.lineTo(bx + bw + 4, py); ctx.stroke();
      ctx.fillText(cl[k], bx + bw + 6, py);
    });
    if (pic.level >= lo && pic.level <= hi) {
      const py = at(pic.level);
      ctx.strokeStyle = "#fff"; ctx.lineWidth = 2; ctx.setLineDash([4, 3]);
      ctx.beginPath(); ctx.moveTo(bx, py); ctx.lineTo(bx + bw, py); ctx.stroke(); ctx.setLineDash([]);
    }
  }
  ctx.save(); ctx.translate(canvas.width - 8, m.t + H / 2); ctx.rotate(-Math.PI / 2);
  ctx.fillStyle = "#222"; ctx.textAlign = "center"; ctx.textBaseline = "bottom";
  ctx.fillText(label, 0, 0); ctx.restore();
  canvas.dataset.xTicks = xl.join(" ");
  canvas.dataset.yTicks = yl.join(" ");
  canvas.dataset.colourTicks = cl.join(" ");
  canvas.dataset.colourLabel = label;
  canvas.setAttribute("aria-label", "paths over the field: x " + xl[0] + " to " + xl[xl.length - 1] + " m, y " + yl[0] + " to " + yl[yl.length - 1] + " m, colour " + label);
}
function drawPath(ctx, toPx, xs, ys, col, width) {
  ctx.strokeStyle = col; ctx.lineWidth = width; ctx.beginPath();
  let started = false;
  for (let k = 0; k < xs.length; k++) {
    if (!isFinite(xs[k]) || !isFinite(ys[k])) { started = false; continue; }
    const p = toPx(xs[k], ys[k]);
    if (started) ctx.lineTo(p[0], p[1]); else { ctx.moveTo(p[0], p[1]); started = true; }
  }
  ctx.stroke();
}
function fmt(v, digits) {
  if (v === null || v === undefined || !isFinite(v)) return "n/a";
  const a = Math.abs(v);
  if (a !== 0 && (a < 1e-3 || a >= 1e5)) return v.toExponential(digits === undefined ? 3 : digits);
  return v.toFixed(digits === undefined ? 3 : digits);
}
function el(tag, attrs, text) {
  const e = document.createElement(tag);
  for (const k in (attrs || {})) e.setAttribute(k, attrs[k]);
  if (text !== undefined) e.textContent = text;
  return e;
}
"##;

#[cfg(test)]
mod tests {
    use super::*;

    /// Hostile strings the pages must carry as data, not markup.
    const HOSTILE: [&str; 9] = [
        "<!--<script>",
        "</script><script>alert(1)</script>",
        "<img src=x onerror=alert(1)>",
        "a\u{2028}b\u{2029}c",
        "\"quotes\" 'single' `back`",
        "]]> <![CDATA[",
        "&amp; &lt; \\u003c \\",
        "<\\/script>",
        "a\u{202e}b\u{200b}c\u{e0041}",
    ];

    /// No character that can start markup or end the element is left, and the JSON parses
    /// back to exactly the input.
    #[test]
    fn script_json_leaves_no_markup_and_round_trips() {
        for s in HOSTILE {
            let v = serde_json::json!({ "name": s, "list": [s, s], s: 1.5 });
            let j = script_json(&v);
            for bad in [
                '<',
                '>',
                '&',
                '\u{2028}',
                '\u{2029}',
                '\u{202e}',
                '\u{e0041}',
            ] {
                assert!(!j.contains(bad), "{bad:?} left in {j}");
            }
            let back: serde_json::Value = serde_json::from_str(&j).unwrap();
            assert_eq!(back, v, "{j}");
        }
        // By hand: each character's escape.
        assert_eq!(
            escape_script_json("\"<!--<a&b>\u{2028}\u{2029}\""),
            r#""\u003c!--\u003ca\u0026b\u003e\u2028\u2029""#
        );
        assert_eq!(
            escape_script_json("\"\u{202e}\u{e0041}\""),
            r#""\u202e\udb40\udc41""#
        );
        // An escaped backslash before `<` stays a backslash and a `<`.
        let j = script_json(&"\\<");
        assert_eq!(j, r#""\\\u003c""#);
        assert_eq!(serde_json::from_str::<String>(&j).unwrap(), "\\<");
    }

    #[test]
    fn escape_covers_content_and_both_quotes() {
        assert_eq!(
            escape("<a href='x' title=\"y\">&</a>"),
            "&lt;a href=&#39;x&#39; title=&quot;y&quot;&gt;&amp;&lt;/a&gt;"
        );
    }

    /// Issue 30 (att30b item 13): a run directory's name with ESC or U+202E reached the
    /// report's `<title>` and `<h1>` raw (the U+202E reversing the heading); every character
    /// the one plain-text rule refuses is shown as its escape, as on the console.
    #[test]
    fn escape_shows_controls_and_invisibles_as_escapes() {
        assert_eq!(escape("d\u{202e}<x>"), "d\\u{202e}&lt;x&gt;");
        assert_eq!(escape("d\u{1b}[31m"), "d\\x1b[31m");
        assert_eq!(escape("a\u{2028}b\u{200b}"), "a\\u{2028}b\\u{200b}");
        assert_eq!(escape("plain é 中"), "plain é 中");
    }
}
