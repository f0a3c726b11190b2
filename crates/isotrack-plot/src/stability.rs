//! The stability chart of `isotrack check --map`: the sampled loop's spectral radius over `kp`
//! (log axis) x sensor rate (log axis, Hz), the boundary (radius 1) by marching squares on the
//! grid, cells not computed hatched grey, the scenario's point, and `--verify` outcomes.

use crate::style::Format;
use crate::style::{tick_label, value_label, Style};
use crate::{fonts, PlotError};
use isotrack_scenario::check::map::{Behaviour, CellStatus, StabilityMap, VerifyPoint};
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

/// The corner of the chart with the fewest verification points and boundary points in its
/// third of each axis (in `ln kp`, `ln rate`): where the legend hides the least.
fn legend_corner(map: &StabilityMap, verify: &[VerifyPoint]) -> SeriesLabelPosition {
    let [k0, k1] = map.grid.kp_range;
    let [r0, r1] = map.grid.rate_range_hz;
    let unit = |x: f64, lo: f64, hi: f64| (x / lo).ln() / (hi / lo).ln();
    let mut pts: Vec<(f64, f64)> = verify.iter().map(|p| (p.kp, p.rate_hz)).collect();
    pts.extend(boundary_segments(map).into_iter().flatten());
    let count = |right: bool, top: bool| {
        pts.iter()
            .filter(|&&(k, r)| {
                let (u, v) = (unit(k, k0, k1), unit(r, r0, r1));
                (if right { u > 0.55 } else { u < 0.45 }) && (if top { v > 0.65 } else { v < 0.35 })
            })
            .count()
    };
    [
        (SeriesLabelPosition::UpperRight, count(true, true)),
        (SeriesLabelPosition::UpperLeft, count(false, true)),
        (SeriesLabelPosition::LowerRight, count(true, false)),
        (SeriesLabelPosition::LowerLeft, count(false, false)),
    ]
    .into_iter()
    .min_by_key(|c| c.1)
    .map_or(SeriesLabelPosition::UpperRight, |c| c.0)
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
    match st.format {
        Format::Png => {
            let root = BitMapBackend::new(path, (w, h)).into_drawing_area();
            draw(chart(&root, map, verify, st).and_then(|_| root.present().map_err(s)))
        }
        Format::Svg => {
            let root = SVGBackend::new(path, (w, h)).into_drawing_area();
            draw(
                chart(&root, map, verify, st)
                    .and_then(|_| root.present().map_err(s))
                    .and_then(|_| crate::style::svg_without_controls(path)),
            )
        }
    }
}

fn chart<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    map: &StabilityMap,
    verify: &[VerifyPoint],
    st: &Style,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(s)?;
    let f = st.base_font();
    let (w, h) = root.dim_in_pixel();
    let [ki, c1, c2] = map.other_gains;
    let default_title = "Sampled-loop stability: spectral radius over kp and sensor rate";
    let title = st.title(default_title);
    let chars = title.chars().count() as f64;
    let title_rel = (1.4 * (w as f64 / (0.62 * f)) / chars.max(1.0)).clamp(0.7, 1.4);
    // The caption below the plot: what the chart shows (which slopes) and the fixed gains.
    let caption = [
        format!("radius on {}", map.slope_basis),
        format!(
            "ki = {}, c1 = {}, c2 = {}, delay {} s; black: radius 1; grey hatch: not computed",
            value_label(ki),
            value_label(c1),
            value_label(c2),
            value_label(map.delay_s)
        ),
    ];
    let foot = (2.0 * 1.25 * 0.85 * f + 0.6 * f) as u32;
    let (body, footer) = root.split_vertically(h - foot);
    let bar_w = (7.5 * f) as u32;
    let (left, right) = body.split_horizontally(w.saturating_sub(bar_w));
    let [k0, k1] = map.grid.kp_range;
    let [r0, r1] = map.grid.rate_range_hz;
    let mut ch = ChartBuilder::on(&left)
        .margin(f as u32)
        .margin_right((1.5 * f) as u32)
        .caption(title, st.font(title_rel))
        .x_label_area_size((3.2 * f) as u32)
        .y_label_area_size((4.8 * f) as u32)
        .build_cartesian_2d((k0..k1).log_scale(), (r0..r1).log_scale())
        .map_err(s)?;
    ch.configure_mesh()
        .disable_mesh()
        .x_desc("kp (log scale)")
        .y_desc("sensor rate, Hz (log scale)")
        .x_label_formatter(&|v| log_tick(*v))
        .y_label_formatter(&|v| log_tick(*v))
        .label_style(st.font(0.95))
        .axis_desc_style(st.font(1.0))
        .draw()
        .map_err(s)?;
    // The cells as one image: each pixel takes the nearest grid point in (ln kp, ln rate).
    let (pw, ph) = ch.plotting_area().dim_in_pixel();
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
                CellStatus::NoEquilibrium => st.colormap.colour(TOP, 0.0, TOP),
                _ => st
                    .colormap
                    .colour(c.spectral_radius.unwrap_or(TOP).min(TOP), 0.0, TOP),
            };
            let o = ((py * pw + px) * 3) as usize;
            buf[o..o + 3].copy_from_slice(&[rgb.0, rgb.1, rgb.2]);
        }
    }
    if let Some(img) = BitMapElement::with_owned_buffer((k0, r1), (pw, ph), buf) {
        ch.draw_series(std::iter::once(img)).map_err(s)?;
    }
    let bold = st.px(3.0);
    ch.draw_series(
        boundary_segments(map)
            .into_iter()
            .map(|[a, b]| PathElement::new(vec![a, b], BLACK.stroke_width(bold))),
    )
    .map_err(s)?
    .label("spectral radius 1 (the boundary)")
    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(bold)));
    // The verification runs: shape by behaviour, white where the chart agrees, red where not.
    let r = st.px(5.0);
    let red = RGBColor(214, 39, 40);
    let grey = RGBColor(150, 150, 150);
    // Red: the run disagrees with the chart; grey: not compared (not computed there).
    let mark = |p: &VerifyPoint, agree: RGBColor| match p.agrees {
        Some(false) => red,
        None => grey,
        Some(true) => agree,
    };
    let fill = |p: &VerifyPoint| mark(p, WHITE);
    let shown = |b: Behaviour| verify.iter().filter(move |p| p.behaviour == b);
    let edge = st.px(1.5);
    if verify.iter().any(|p| p.behaviour == Behaviour::Converged) {
        ch.draw_series(shown(Behaviour::Converged).flat_map(|p| {
            [
                Circle::new((p.kp, p.rate_hz), r, fill(p).filled()),
                Circle::new((p.kp, p.rate_hz), r, BLACK.stroke_width(edge)),
            ]
        }))
        .map_err(s)?
        .label("run converged")
        .legend(move |(x, y)| Circle::new((x + 10, y), r, BLACK.stroke_width(edge)));
    }
    if verify.iter().any(|p| p.behaviour == Behaviour::LimitCycle) {
        ch.draw_series(shown(Behaviour::LimitCycle).map(|p| {
            let c = mark(p, BLACK);
            TriangleMarker::new((p.kp, p.rate_hz), r + 1, c.filled())
        }))
        .map_err(s)?
        .label("run in a limit cycle")
        .legend(move |(x, y)| TriangleMarker::new((x + 10, y), r + 1, BLACK.filled()));
    }
    if verify.iter().any(|p| p.behaviour == Behaviour::Diverged) {
        ch.draw_series(shown(Behaviour::Diverged).map(|p| {
            let c = mark(p, BLACK);
            Cross::new((p.kp, p.rate_hz), r, c.stroke_width(st.px(2.5)))
        }))
        .map_err(s)?
        .label("run diverged")
        .legend(move |(x, y)| Cross::new((x + 10, y), r, BLACK.stroke_width(edge)));
    }
    if verify.iter().any(|p| p.agrees == Some(false)) {
        ch.draw_series(std::iter::empty::<Circle<(f64, f64), u32>>())
            .map_err(s)?
            .label("red: the run disagrees with the chart")
            .legend(move |(x, y)| Circle::new((x + 10, y), r, red.filled()));
    }
    if verify
        .iter()
        .any(|p| p.agrees.is_none() && p.behaviour != Behaviour::Invalid)
    {
        ch.draw_series(std::iter::empty::<Circle<(f64, f64), u32>>())
            .map_err(s)?
            .label("grey: not compared (cell not computed)")
            .legend(move |(x, y)| Circle::new((x + 10, y), r, grey.filled()));
    }
    // The scenario's own point.
    let (kp, rate) = map.scenario_point;
    let star = st.px(9.0);
    ch.draw_series([
        Circle::new(
            (kp, rate),
            star,
            RGBColor(255, 127, 14).stroke_width(st.px(3.0)),
        ),
        Circle::new((kp, rate), st.px(2.5), RGBColor(255, 127, 14).filled()),
    ])
    .map_err(s)?
    .label(format!(
        "scenario: kp = {}, {} Hz",
        value_label(kp),
        value_label(rate)
    ))
    .legend(move |(x, y)| {
        Circle::new(
            (x + 10, y),
            star.min(8),
            RGBColor(255, 127, 14).stroke_width(3),
        )
    });
    ch.configure_series_labels()
        .position(legend_corner(map, verify))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(st.font(0.85))
        .draw()
        .map_err(s)?;
    // Colour bar: radius 0 .. 2, the boundary at 1.
    let mut bar = ChartBuilder::on(&right)
        .margin_top((f + 2.4 * f * title_rel) as u32)
        .margin_bottom((f + 3.2 * f) as u32)
        .margin_left((0.5 * f) as u32)
        .margin_right((2.0 * f) as u32)
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
        Rectangle::new(
            [(0.0, a), (1.0, b)],
            st.colormap.colour(0.5 * (a + b), 0.0, TOP).filled(),
        )
    }))
    .map_err(s)?;
    bar.draw_series(std::iter::once(PathElement::new(
        vec![(0.0, 1.0), (1.0, 1.0)],
        BLACK.stroke_width(bold),
    )))
    .map_err(s)?;
    // The caption.
    let style = TextStyle::from(st.font(0.85)).color(&BLACK);
    for (k, line) in caption.iter().enumerate() {
        footer
            .draw_text(
                line,
                &style,
                (f as i32, (k as f64 * 1.25 * 0.85 * f) as i32),
            )
            .map_err(s)?;
    }
    Ok(())
}
