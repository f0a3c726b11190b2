//! # isotrack-html
//!
//! Self-contained HTML pages: the data as JSON in the page, inline CSS and JavaScript, no
//! network and no CDN, so a page works from `file://` and can be mailed or archived.
//!
//! * [`benchmark_page`]: a benchmark's `index.html` (sortable leaderboard, per-task tables,
//!   a picture of each task's paths over its field).
//! * [`report_page`]: one or more runs (field heat map with the target isoline, the paths, a
//!   play/pause time slider, error / measurement / turn-rate plots on the same cursor, hover
//!   values with units).
//!
//! Hand-written: the pages are small and fixed, and a templating or charting library would
//! either fetch scripts from the network or add more code than the pages themselves.
#![deny(missing_docs)]

mod benchmark;
mod report;

pub use benchmark::benchmark_page;
pub use report::{report_page, ReportError};

/// Text escaped for HTML element content and quoted attribute values (`&`, `<`, `>`, `"`, `'`).
pub(crate) fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&#39;")
}

/// JSON safe inside `<script type="application/json">`: every `<`, `>` and `&` is written as
/// `\u003c`, `\u003e`, `\u0026`, and U+2028 / U+2029 as `\u2028` / `\u2029`.
///
/// Escaping only `</` is not enough: `<!--` followed by `<script` puts the HTML parser in the
/// "script data double escaped" state (WHATWG HTML, 13.2.5.20 ff.), where `</script>` no
/// longer closes the element, so the data swallows the page's scripts. With no `<` left in
/// the element's text no tag or comment can start in it. These characters occur in JSON only
/// inside strings, where `\uXXXX` is the same character to `JSON.parse`, so the data is
/// unchanged. (U+2028/9 are line terminators to pre-2019 JavaScript.)
pub(crate) fn script_json<T: serde::Serialize>(v: &T) -> String {
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
            c => out.push(c),
        }
    }
    out
}

/// The page shell: title, CSS, the data, the shared script, the page's script.
pub(crate) fn page(title: &str, body: &str, data_json: &str, script: &str) -> String {
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
body { font-family: "DejaVu Sans", Arial, sans-serif; margin: 1.5em auto; max-width: 1180px; color: #222; padding: 0 1em; }
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
.mapbox { max-width: 522px; }
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
// coloured over pic.range [lo, hi] if given (else the values' own range).
// Returns a function from metres to canvas pixels.
function drawField(canvas, pic) {
  const ctx = canvas.getContext("2d"), W = canvas.width, H = canvas.height;
  const [x0, y0, x1, y1] = pic.bounds_m;
  const toPx = (x, y) => [(x - x0) / (x1 - x0) * W, H - (y - y0) / (y1 - y0) * H];
  ctx.fillStyle = "#ddd"; ctx.fillRect(0, 0, W, H);
  const vals = pic.values.filter(v => v !== null && isFinite(v));
  if (vals.length > 0) {
    let lo = Infinity, hi = -Infinity;
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
    ctx.drawImage(off, 0, 0, W, H);
  }
  ctx.strokeStyle = "#ffffff"; ctx.lineWidth = 2; ctx.setLineDash([6, 4]);
  ctx.beginPath();
  for (const s of pic.isoline) {
    const a = toPx(s[0], s[1]), b = toPx(s[2], s[3]);
    ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]);
  }
  ctx.stroke(); ctx.setLineDash([]);
  return toPx;
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
    const HOSTILE: [&str; 8] = [
        "<!--<script>",
        "</script><script>alert(1)</script>",
        "<img src=x onerror=alert(1)>",
        "a\u{2028}b\u{2029}c",
        "\"quotes\" 'single' `back`",
        "]]> <![CDATA[",
        "&amp; &lt; \\u003c \\",
        "<\\/script>",
    ];

    /// No character that can start markup or end the element is left, and the JSON parses
    /// back to exactly the input.
    #[test]
    fn script_json_leaves_no_markup_and_round_trips() {
        for s in HOSTILE {
            let v = serde_json::json!({ "name": s, "list": [s, s], s: 1.5 });
            let j = script_json(&v);
            for bad in ['<', '>', '&', '\u{2028}', '\u{2029}'] {
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
}
