//! The stability chart of `isotrack check --map`: the sampled loop's spectral radius over `kp`
//! (log axis) x sensor rate (log axis, Hz), the boundary (radius 1) by marching squares on the
//! grid, cells not computed hatched grey, the scenario's point, and `--verify` outcomes.

use crate::style::Format;
use crate::style::{tick_label, value_label, Style};
use crate::{fonts, PlotError};
use isotrack_scenario::check::map::{Behaviour, CellStatus, StabilityMap, VerifyPoint};
use plotters::coord::combinators::WithKeyPoints;
use plotters::prelude::*;
use std::path::Path;

fn s<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// The radius a colour stands for: the spectral radius clipped to `[0, 2]` (no equilibrium:
/// 2).
const TOP: f64 = 2.0;

/// A log-axis tick label: the value with the digits a tenth of it needs (`0.1`, `20`, `1e3`).
fn log_tick(v: f64) -> String {
    tick_label(v, v.abs() / 10.0)
}

/// The chart's diverging colour for radius `r` (clipped to `[0, TOP]`): blue below 1 (dark at
/// 0, light just below 1), red from 1 up (light just above 1, dark at 2 or more), so stable and
/// unstable never share a colour (ColorBrewer RdBu's ends and its light steps).
pub fn radius_colour(r: f64) -> RGBColor {
    let lerp = |a: (u8, u8, u8), b: (u8, u8, u8), t: f64| {
        let t = t.clamp(0.0, 1.0);
        let m = |x: u8, y: u8| (f64::from(x) + t * (f64::from(y) - f64::from(x))).round() as u8;
        RGBColor(m(a.0, b.0), m(a.1, b.1), m(a.2, b.2))
    };
    if r < 1.0 {
        lerp((33, 102, 172), (209, 229, 240), r.max(0.0))
    } else {
        lerp(
            (253, 219, 199),
            (178, 24, 43),
            (r.min(TOP) - 1.0) / (TOP - 1.0),
        )
    }
}

/// Tick values for a log axis from `lo` to `hi`: on a range of less than a decade 1 to 9 times
/// the powers of ten within it (2, 3, 4, 5 on 2 .. 5); otherwise the powers of ten (every
/// `step`-th when there are many) with 2 and 5 times them when they leave room; failing all,
/// the ends and their geometric middle: never fewer than 2 ticks. `room` is the most labels the axis holds without overlap.
pub fn log_ticks(lo: f64, hi: f64, room: usize) -> Vec<f64> {
    let room = room.max(2);
    let inside = |v: &f64| *v >= lo * (1.0 - 1e-9) && *v <= hi * (1.0 + 1e-9);
    let (e0, e1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let with = |mults: &[f64]| -> Vec<f64> {
        (e0..=e1)
            .flat_map(|e| mults.iter().map(move |m| m * 10f64.powi(e)))
            .filter(inside)
            .collect()
    };
    let fine_first = hi / lo < 10.0;
    let order: [&[f64]; 3] = if fine_first {
        [
            &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
            &[1.0, 2.0, 5.0],
            &[1.0],
        ]
    } else {
        [
            &[1.0, 2.0, 5.0],
            &[1.0],
            &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
        ]
    };
    for mults in order {
        let t = with(mults);
        if t.len() >= 2 && t.len() <= room {
            return t;
        }
    }
    let decades = with(&[1.0]);
    if decades.len() > room {
        let step = decades.len().div_ceil(room);
        return decades.into_iter().step_by(step).collect();
    }
    let fine = with(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    if fine.len() >= 2 {
        let step = fine.len().div_ceil(room);
        return fine.into_iter().step_by(step).collect();
    }
    // Less than one step of 1..9 x 10^k: the ends and the geometric middle.
    vec![lo, (lo * hi).sqrt(), hi]
}

/// A tick's label with the digits its neighbours need to differ.
fn tick_text(v: f64, ticks: &[f64]) -> String {
    let gap = ticks
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .fold(f64::INFINITY, f64::min);
    if gap.is_finite() {
        tick_label(v, gap.min(v.abs() / 10.0))
    } else {
        log_tick(v)
    }
}

/// Segments of the level `rho = 1` by marching squares on the grid in `(ln kp, ln rate)`,
/// linear interpolation along each edge; squares with a corner not computed are left out.
/// Returns pairs of `(kp, rate)` points.
pub fn boundary_segments(map: &StabilityMap) -> Vec<[(f64, f64); 2]> {
    let (nk, nr) = (map.kps.len(), map.rates_hz.len());
    let value = |i: usize, j: usize| -> Option<f64> {
        let c = map.at(i, j);
        match c.status {
            CellStatus::NotComputed => None,
            CellStatus::NoEquilibrium => Some(TOP - 1.0),
            _ => c.spectral_radius.map(|r| r.min(TOP) - 1.0),
        }
    };
    let lk: Vec<f64> = map.kps.iter().map(|k| k.ln()).collect();
    let lr: Vec<f64> = map.rates_hz.iter().map(|r| r.ln()).collect();
    let mut out = vec![];
    for j in 0..nr.saturating_sub(1) {
        for i in 0..nk.saturating_sub(1) {
            let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let Some(v): Option<Vec<f64>> = corners.iter().map(|&(a, b)| value(a, b)).collect()
            else {
                continue;
            };
            let mut pts = vec![];
            for e in 0..4 {
                let (a, b) = (e, (e + 1) % 4);
                // Stable is `v < 0`, as the check's `rho < 1`.
                if (v[a] < 0.0) != (v[b] < 0.0) {
                    let t = (v[a] / (v[a] - v[b])).clamp(0.0, 1.0);
                    let (pa, pb) = (corners[a], corners[b]);
                    let x = lk[pa.0] + t * (lk[pb.0] - lk[pa.0]);
                    let y = lr[pa.1] + t * (lr[pb.1] - lr[pa.1]);
                    pts.push((x.exp(), y.exp()));
                }
            }
            for pair in pts.chunks_exact(2) {
                out.push([pair[0], pair[1]]);
            }
        }
    }
    out
}

/// Draws the chart (`verify`: the `--verify` points, possibly none) into `path`.
pub fn stability_map_figure(
    map: &StabilityMap,
    verify: &[VerifyPoint],
    path: &Path,
    st: &Style,
) -> Result<(), PlotError> {
    fonts();
    let draw = |res: Result<(), String>| {
        res.map_err(|message| PlotError::Draw {
            path: path.display().to_string(),
            message,
        })
    };
    let (w, h) = st.size((1000, 800), (560, 470));
    // Never through a link nor into a FIFO: `draw::draw_atomic`.
    draw(crate::draw::draw_atomic(path, |path| match st.format {
        Format::Png => {
            let root =
                crate::bitmap::SafeLines(BitMapBackend::new(path, (w, h))).into_drawing_area();
            chart(&root, map, verify, st).and_then(|_| root.present().map_err(s))
        }
        Format::Svg => {
            let root = SVGBackend::new(path, (w, h)).into_drawing_area();
            chart(&root, map, verify, st)
                .and_then(|_| root.present().map_err(s))
                .and_then(|_| crate::style::svg_without_controls(path))
        }
    }))
}

/// One legend entry's marker (drawn below the plot, never over the data).
#[derive(Clone, Copy)]
enum Key {
    Line,
    Converged,
    LimitCycle,
    Diverged,
    LeftField,
    Disagrees,
    NotCompared,
    Scenario,
}

/// The chart's marker colours: a run the chart disagrees with, a run not compared, and the
/// scenario's own point.
const RED: RGBColor = RGBColor(214, 39, 40);
const GREY: RGBColor = RGBColor(150, 150, 150);
const ORANGE: RGBColor = RGBColor(255, 127, 14);

/// The plot's coordinates: log `kp` by log sensor rate, each with its chosen ticks.
type MapChart<'a, DB> =
    ChartContext<'a, DB, Cartesian2d<WithKeyPoints<LogCoord<f64>>, WithKeyPoints<LogCoord<f64>>>>;

/// The whole chart: the plot (cells, boundary, `--verify` runs, the scenario's point) with its
/// colour bar on the right, the legend and the caption below, each drawn by one function.
fn chart<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    map: &StabilityMap,
    verify: &[VerifyPoint],
    st: &Style,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(s)?;
    let f = st.base_font();
    let (w, h) = root.dim_in_pixel();
    let default_title = "Sampled-loop stability: spectral radius over kp and sensor rate";
    let title = st.title(default_title);
    let chars = title.chars().count() as f64;
    let title_rel = (1.4 * (w as f64 / (0.62 * f)) / chars.max(1.0)).clamp(0.7, 1.4);
    let outside = outside_the_chart(map);
    let keys = legend_keys(map, verify, outside);
    let caption = caption_lines(map, outside);
    let line_h = 1.25 * 0.85 * f;
    let per_row = 3usize;
    let key_rows = keys.len().div_ceil(per_row);
    let foot = ((caption.len() + key_rows) as f64 * line_h + 1.2 * f) as u32;
    let (body, footer) = root.split_vertically(h - foot);
    let bar_w = (9.5 * f) as u32;
    let (left, right) = body.split_horizontally(w.saturating_sub(bar_w));
    let mut ch = axes(&left, map, title, title_rel, st)?;
    draw_cells(&mut ch, map)?;
    let bold = st.px(3.0);
    ch.draw_series(
        boundary_segments(map)
            .into_iter()
            .map(|[a, b]| PathElement::new(vec![a, b], BLACK.stroke_width(bold))),
    )
    .map_err(s)?;
    draw_verify_runs(&mut ch, verify, st)?;
    draw_scenario_point(&mut ch, map, outside, st)?;
    colour_bar(&right, title_rel, st)?;
    legend_and_caption(&footer, &keys, &caption, st)
}

/// Whether the scenario's own point lies outside the chart's ranges (it is then an arrow at the
/// edge).
fn outside_the_chart(map: &StabilityMap) -> bool {
    let [k0, k1] = map.grid.kp_range;
    let [r0, r1] = map.grid.rate_range_hz;
    let (kp, rate) = map.scenario_point;
    !(k0..=k1).contains(&kp) || !(r0..=r1).contains(&rate)
}

/// The legend's entries (only those on the chart), drawn in rows below the plot.
fn legend_keys(map: &StabilityMap, verify: &[VerifyPoint], outside: bool) -> Vec<(Key, String)> {
    let (kp, rate) = map.scenario_point;
    let any = |b: Behaviour| verify.iter().any(|p| p.behaviour == b);
    let mut keys: Vec<(Key, String)> = vec![(Key::Line, "spectral radius 1 (the boundary)".into())];
    for (b, k, label) in [
        (Behaviour::Converged, Key::Converged, "run converged"),
        (
            Behaviour::LimitCycle,
            Key::LimitCycle,
            "run in a limit cycle",
        ),
        (
            Behaviour::Stalled,
            Key::LimitCycle,
            "run stalled off the level (triangle)",
        ),
        (Behaviour::Diverged, Key::Diverged, "run diverged"),
        (
            Behaviour::LeftField,
            Key::LeftField,
            "run left the field (not compared)",
        ),
        (
            Behaviour::Saturated,
            Key::LimitCycle,
            "grey triangle: run saturated the turn-rate limit (not compared)",
        ),
        (
            Behaviour::Undetermined,
            Key::Converged,
            "grey circle: run too short to judge (not compared)",
        ),
    ] {
        if any(b) {
            keys.push((k, label.into()));
        }
    }
    if verify.iter().any(|p| p.agrees == Some(false)) {
        keys.push((
            Key::Disagrees,
            "red: the run disagrees with the chart".into(),
        ));
    }
    if verify.iter().any(|p| {
        p.agrees.is_none()
            && !matches!(
                p.behaviour,
                Behaviour::Invalid
                    | Behaviour::LeftField
                    | Behaviour::Saturated
                    | Behaviour::Undetermined
            )
    }) {
        keys.push((
            Key::NotCompared,
            "grey: not compared (cell not computed)".into(),
        ));
    }
    keys.push((
        Key::Scenario,
        format!(
            "scenario: kp = {}, {} Hz{}",
            value_label(kp),
            value_label(rate),
            if outside {
                " (outside the chart: arrow at the edge)"
            } else {
                ""
            }
        ),
    ));
    keys
}

/// The caption below the plot: what the chart shows (which slopes) and the fixed gains.
fn caption_lines(map: &StabilityMap, outside: bool) -> Vec<String> {
    let [ki, c1, c2] = map.other_gains;
    let (kp, rate) = map.scenario_point;
    let mut caption = vec![
        format!("radius on {}", map.slope_basis),
        format!(
            "ki = {}, c1 = {}, c2 = {}, delay {} s; blue: stable (radius < 1), red: unstable; grey hatch: not computed",
            value_label(ki),
            value_label(c1),
            value_label(c2),
            value_label(map.delay_s)
        ),
    ];
    if outside {
        caption.push(format!(
            "the scenario's point (kp = {}, {} Hz) lies outside the chart's ranges: the arrow at the edge points towards it",
            value_label(kp),
            value_label(rate)
        ));
    }
    caption
}

/// The plot's axes (log `kp` by log rate, a little wider than the grid) with their ticks and
/// titles.
fn axes<'a, DB: DrawingBackend>(
    left: &'a DrawingArea<DB, plotters::coord::Shift>,
    map: &StabilityMap,
    title: &str,
    title_rel: f64,
    st: &Style,
) -> Result<MapChart<'a, DB>, String> {
    let f = st.base_font();
    let [k0, k1] = map.grid.kp_range;
    let [r0, r1] = map.grid.rate_range_hz;
    // Axes a little wider than the grid (3 % of each log span a side): markers at the grid's
    // edge are drawn whole.
    let pad = |lo: f64, hi: f64| {
        let e = (hi / lo).powf(0.03);
        (lo / e, hi * e)
    };
    let (xk0, xk1) = pad(k0, k1);
    let (yr0, yr1) = pad(r0, r1);
    let (lw, _) = left.dim_in_pixel();
    let xroom = ((lw as f64 - 6.0 * f) / (4.5 * f)).floor().max(2.0) as usize;
    let yroom = 9;
    let xt = log_ticks(k0, k1, xroom);
    let yt = log_ticks(r0, r1, yroom);
    let mut ch = ChartBuilder::on(left)
        .margin(f as u32)
        .margin_right((1.5 * f) as u32)
        .caption(title, st.font(title_rel))
        .x_label_area_size((3.2 * f) as u32)
        .y_label_area_size((4.8 * f) as u32)
        .build_cartesian_2d(
            (xk0..xk1).log_scale().with_key_points(xt.clone()),
            (yr0..yr1).log_scale().with_key_points(yt.clone()),
        )
        .map_err(s)?;
    ch.configure_mesh()
        .disable_mesh()
        .x_desc("kp (log scale)")
        .y_desc("sensor rate, Hz (log scale)")
        .x_label_formatter(&|v| tick_text(*v, &xt))
        .y_label_formatter(&|v| tick_text(*v, &yt))
        .label_style(st.font(0.95))
        .axis_desc_style(st.font(1.0))
        .draw()
        .map_err(s)?;
    Ok(ch)
}

/// The cells as one image over the grid's extent: each pixel takes the nearest grid point in
/// `(ln kp, ln rate)`; cells not computed hatched grey.
fn draw_cells<DB: DrawingBackend>(
    ch: &mut MapChart<'_, DB>,
    map: &StabilityMap,
) -> Result<(), String> {
    let [k0, k1] = map.grid.kp_range;
    let [r0, r1] = map.grid.rate_range_hz;
    // The cells as one image over the grid's extent: each pixel takes the nearest grid point
    // in (ln kp, ln rate).
    let (px0, py0) = ch.backend_coord(&(k0, r1));
    let (px1, py1) = ch.backend_coord(&(k1, r0));
    let (pw, ph) = ((px1 - px0).max(1) as u32, (py1 - py0).max(1) as u32);
    let (nk, nr) = (map.kps.len(), map.rates_hz.len());
    let mut buf = vec![255u8; (pw * ph * 3) as usize];
    for py in 0..ph {
        let v = 1.0 - (py as f64 + 0.5) / ph as f64;
        let j = ((v * (nr - 1) as f64).round() as usize).min(nr - 1);
        for px in 0..pw {
            let u = (px as f64 + 0.5) / pw as f64;
            let i = ((u * (nk - 1) as f64).round() as usize).min(nk - 1);
            let c = map.at(i, j);
            let rgb = match c.status {
                CellStatus::NotComputed => {
                    if (px + py) % 8 < 2 {
                        RGBColor(150, 150, 150)
                    } else {
                        RGBColor(225, 225, 225)
                    }
                }
                CellStatus::NoEquilibrium => radius_colour(TOP),
                _ => radius_colour(c.spectral_radius.unwrap_or(TOP)),
            };
            let o = ((py * pw + px) * 3) as usize;
            buf[o..o + 3].copy_from_slice(&[rgb.0, rgb.1, rgb.2]);
        }
    }
    if let Some(img) = BitMapElement::with_owned_buffer((k0, r1), (pw, ph), buf) {
        ch.draw_series(std::iter::once(img)).map_err(s)?;
    }
    Ok(())
}

/// The `--verify` runs: shape by behaviour, white where the chart agrees, red where not, grey
/// where not compared.
fn draw_verify_runs<DB: DrawingBackend>(
    ch: &mut MapChart<'_, DB>,
    verify: &[VerifyPoint],
    st: &Style,
) -> Result<(), String> {
    let (red, grey) = (RED, GREY);
    let r = st.px(5.0);
    let mark = |p: &VerifyPoint, agree: RGBColor| match p.agrees {
        Some(false) => red,
        None => grey,
        Some(true) => agree,
    };
    let shown = |b: Behaviour| verify.iter().filter(move |p| p.behaviour == b);
    let edge = st.px(1.5);
    ch.draw_series(
        shown(Behaviour::Converged)
            .chain(shown(Behaviour::Undetermined))
            .flat_map(|p| {
                [
                    Circle::new((p.kp, p.rate_hz), r, mark(p, WHITE).filled()),
                    Circle::new((p.kp, p.rate_hz), r, BLACK.stroke_width(edge)),
                ]
            }),
    )
    .map_err(s)?;
    ch.draw_series(
        shown(Behaviour::LimitCycle)
            .chain(shown(Behaviour::Stalled))
            .chain(shown(Behaviour::Saturated))
            .map(|p| TriangleMarker::new((p.kp, p.rate_hz), r + 1, mark(p, BLACK).filled())),
    )
    .map_err(s)?;
    ch.draw_series(shown(Behaviour::Diverged).map(|p| {
        Cross::new(
            (p.kp, p.rate_hz),
            r,
            mark(p, BLACK).stroke_width(st.px(2.5)),
        )
    }))
    .map_err(s)?;
    ch.draw_series(shown(Behaviour::LeftField).map(|p| {
        let (x, y) = (p.kp, p.rate_hz);
        let q = r as i32;
        EmptyElement::at((x, y)) + Rectangle::new([(-q, -q), (q, q)], grey.stroke_width(edge))
    }))
    .map_err(s)?;
    Ok(())
}

/// The scenario's own point; outside the chart, an arrow at the edge pointing to it.
fn draw_scenario_point<DB: DrawingBackend>(
    ch: &mut MapChart<'_, DB>,
    map: &StabilityMap,
    outside: bool,
    st: &Style,
) -> Result<(), String> {
    let [k0, k1] = map.grid.kp_range;
    let [r0, r1] = map.grid.rate_range_hz;
    let (kp, rate) = map.scenario_point;
    let orange = ORANGE;
    // The scenario's own point; outside the chart, an arrow at the edge pointing to it.
    let star = st.px(9.0);
    if outside {
        let (cx, cy) = (kp.clamp(k0, k1), rate.clamp(r0, r1));
        let dx: i32 = if kp > k1 {
            1
        } else if kp < k0 {
            -1
        } else {
            0
        };
        let dy: i32 = if rate > r1 {
            -1
        } else if rate < r0 {
            1
        } else {
            0
        };
        let star = star as i32;
        let l = 2 * star;
        let tip = (dx * l, dy * l);
        let back = (-dy * star / 2, dx * star / 2);
        ch.draw_series(std::iter::once(
            EmptyElement::at((cx, cy))
                + PathElement::new(vec![(0, 0), tip], orange.stroke_width(st.px(3.0)))
                + Polygon::new(
                    vec![
                        (tip.0 + dx * star / 2, tip.1 + dy * star / 2),
                        (tip.0 + back.0, tip.1 + back.1),
                        (tip.0 - back.0, tip.1 - back.1),
                    ],
                    orange.filled(),
                ),
        ))
        .map_err(s)?;
    } else {
        ch.draw_series([
            Circle::new((kp, rate), star, orange.stroke_width(st.px(3.0))),
            Circle::new((kp, rate), st.px(2.5), orange.filled()),
        ])
        .map_err(s)?;
    }
    Ok(())
}

/// The colour bar on the right: radius 0 .. 2, the boundary at 1.
fn colour_bar<DB: DrawingBackend>(
    right: &DrawingArea<DB, plotters::coord::Shift>,
    title_rel: f64,
    st: &Style,
) -> Result<(), String> {
    let f = st.base_font();
    let bold = st.px(3.0);
    // Colour bar: radius 0 .. 2, the boundary at 1.
    let mut bar = ChartBuilder::on(right)
        .margin_top((f + 2.4 * f * title_rel) as u32)
        .margin_bottom((f + 3.2 * f) as u32)
        .margin_left((0.5 * f) as u32)
        .margin_right((1.0 * f) as u32)
        .y_label_area_size((3.6 * f) as u32)
        .build_cartesian_2d(0.0..1.0, 0.0..TOP)
        .map_err(s)?;
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_labels(5)
        .y_desc("spectral radius (2: 2 or more)")
        .y_label_formatter(&|v| tick_label(*v, 0.5))
        .label_style(st.font(0.9))
        .axis_desc_style(st.font(0.95))
        .draw()
        .map_err(s)?;
    let n = 100;
    bar.draw_series((0..n).map(|k| {
        let a = TOP * k as f64 / n as f64;
        let b = TOP * (k + 1) as f64 / n as f64;
        Rectangle::new([(0.0, a), (1.0, b)], radius_colour(0.5 * (a + b)).filled())
    }))
    .map_err(s)?;
    bar.draw_series(std::iter::once(PathElement::new(
        vec![(0.0, 1.0), (1.0, 1.0)],
        BLACK.stroke_width(bold),
    )))
    .map_err(s)?;
    Ok(())
}

/// The legend (`keys`, three to a row), then the caption, below the plot.
fn legend_and_caption<DB: DrawingBackend>(
    footer: &DrawingArea<DB, plotters::coord::Shift>,
    keys: &[(Key, String)],
    caption: &[String],
    st: &Style,
) -> Result<(), String> {
    let f = st.base_font();
    let w = footer.dim_in_pixel().0;
    let line_h = 1.25 * 0.85 * f;
    let per_row = 3usize;
    let key_rows = keys.len().div_ceil(per_row);
    let (bold, edge) = (st.px(3.0), st.px(1.5));
    let (red, grey, orange) = (RED, GREY, ORANGE);
    // The legend, then the caption, below the plot.
    let style = TextStyle::from(st.font(0.85)).color(&BLACK);
    let col_w = (w as f64 - 2.0 * f) / per_row as f64;
    for (k, (key, label)) in keys.iter().enumerate() {
        let x = (f + (k % per_row) as f64 * col_w) as i32;
        let y = ((k / per_row) as f64 * line_h + 0.3 * f) as i32;
        let (mx, my) = (x + (0.9 * f) as i32, y + (0.45 * f) as i32);
        let m = (0.45 * f) as i32;
        let res = match key {
            Key::Line => footer.draw(&PathElement::new(
                vec![(mx - m - 4, my), (mx + m + 4, my)],
                BLACK.stroke_width(bold),
            )),
            Key::Converged => footer.draw(&Circle::new((mx, my), m, BLACK.stroke_width(edge))),
            Key::LimitCycle => footer.draw(&TriangleMarker::new((mx, my), m, BLACK.filled())),
            Key::Diverged => footer.draw(&Cross::new((mx, my), m, BLACK.stroke_width(edge))),
            Key::LeftField => footer.draw(&Rectangle::new(
                [(mx - m, my - m), (mx + m, my + m)],
                grey.stroke_width(edge),
            )),
            Key::Disagrees => footer.draw(&Circle::new((mx, my), m, red.filled())),
            Key::NotCompared => footer.draw(&Circle::new((mx, my), m, grey.filled())),
            Key::Scenario => footer.draw(&Circle::new((mx, my), m, orange.stroke_width(3))),
        };
        res.map_err(s)?;
        footer
            .draw_text(label, &style, (x + (2.0 * f) as i32, y))
            .map_err(s)?;
    }
    for (k, line) in caption.iter().enumerate() {
        footer
            .draw_text(
                line,
                &style,
                (f as i32, ((key_rows + k) as f64 * line_h + 0.6 * f) as i32),
            )
            .map_err(s)?;
    }
    Ok(())
}
