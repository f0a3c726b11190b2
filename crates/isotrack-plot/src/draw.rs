//! The figures themselves, drawn with plotters on a PNG or SVG backend.

use crate::run_data::RunData;
use crate::{fonts, PlotError};
use isotrack_core::{ScalarField, Vec2};
use isotrack_fields::isoline::IsolineSegments;
use isotrack_scenario::Scenario;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use std::path::Path;

/// Image format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// PNG (raster).
    Png,
    /// SVG (vector; the heat map is coarser to keep files small).
    Svg,
}

impl Format {
    /// The file extension.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Png => "png",
            Format::Svg => "svg",
        }
    }
}

/// Which time-series panels to draw, top to bottom.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Panels {
    /// Tracking error `eps = s - s_d`.
    pub error: bool,
    /// True field value and last measurement.
    pub measurement: bool,
    /// Measurement rate `ds/dt` (finite differences of the trace).
    pub measurement_rate: bool,
    /// Turn-rate command.
    pub omega: bool,
}

impl Default for Panels {
    fn default() -> Self {
        Self {
            error: true,
            measurement: true,
            measurement_rate: false,
            omega: true,
        }
    }
}

const RUN_COLOURS: [RGBColor; 10] = [
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

fn colour(i: usize) -> RGBColor {
    RUN_COLOURS[i % RUN_COLOURS.len()]
}

type DrawResult = Result<(), String>;

fn s<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// Runs a drawing body on a PNG or a SVG backend of the given size, then writes the file.
macro_rules! render {
    ($path:expr, $format:expr, $size:expr, |$root:ident| $body:expr) => {{
        fonts();
        let path: &Path = $path;
        let res: DrawResult = match $format {
            Format::Png => {
                let $root = BitMapBackend::new(path, $size).into_drawing_area();
                $body.and_then(|_| $root.present().map_err(s))
            }
            Format::Svg => {
                let $root = SVGBackend::new(path, $size).into_drawing_area();
                $body.and_then(|_| $root.present().map_err(s))
            }
        };
        res.map_err(|message| PlotError::Draw {
            path: path.display().to_string(),
            message,
        })
    }};
}

/// A raster of field values over a rectangle: `(x0, y0, cell, nx, ny, values)`.
struct Raster {
    x0: f64,
    y0: f64,
    dx: f64,
    dy: f64,
    nx: usize,
    ny: usize,
    values: Vec<Option<f64>>,
}

impl Raster {
    fn sample(sc: &Scenario, range: [f64; 4], nx: usize, ny: usize) -> Self {
        let dx = (range[1] - range[0]) / nx as f64;
        let dy = (range[3] - range[2]) / ny as f64;
        let mut values = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let p = Vec2::new(
                    range[0] + (i as f64 + 0.5) * dx,
                    range[2] + (j as f64 + 0.5) * dy,
                );
                values.push(sc.field().value(0.0, p));
            }
        }
        Self {
            x0: range[0],
            y0: range[2],
            dx,
            dy,
            nx,
            ny,
            values,
        }
    }
    fn range(&self) -> Option<(f64, f64)> {
        let (lo, hi) = self
            .values
            .iter()
            .flatten()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(*v), b.max(*v))
            });
        // Colours and the colour bar need a finite, non-empty span (values beyond
        // MAX_AXIS_ABS are left to the caller's data check; here they fall back).
        (lo.is_finite() && hi.is_finite() && lo.abs().max(hi.abs()) <= MAX_AXIS_ABS).then(|| {
            let w = if hi > lo { hi - lo } else { 1.0 };
            let w = w.max(1e-9 * lo.abs().max(hi.abs()));
            (lo, lo + w)
        })
    }
}

/// The largest `|value|` an axis may reach. Beyond it widths and pads overflow to infinity and
/// plotters' tick search never ends (a trace at 1e308 once hung `isotrack plot`); the error
/// names the quantity instead.
pub const MAX_AXIS_ABS: f64 = 1.0e100;

/// An axis range for data spanning `[lo, hi]` (finite values only; `None` when there are
/// none): at least `min_width` wide (and 1e-9 of its magnitude, so the ticks stay distinct in
/// `f64`), padded by `pad_frac` of its width on each side; an error naming `what` beyond
/// [`MAX_AXIS_ABS`].
fn padded_axis(
    what: &str,
    lo: f64,
    hi: f64,
    pad_frac: f64,
    min_width: f64,
) -> Result<Option<(f64, f64)>, PlotError> {
    if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
        return Ok(None);
    }
    let mag = lo.abs().max(hi.abs());
    if mag > MAX_AXIS_ABS {
        return Err(PlotError::Data(format!(
            "{what} reaches {:e}, beyond the +-{MAX_AXIS_ABS:e} a plot can show",
            if lo.abs() > hi.abs() { lo } else { hi }
        )));
    }
    let width = (hi - lo).max(min_width).max(1e-9 * mag);
    let mid = 0.5 * (lo + hi);
    let half = 0.5 * width * (1.0 + 2.0 * pad_frac);
    Ok(Some((mid - half, mid + half)))
}

/// Finite `(min, max)` of some values (`(inf, -inf)` when there are none).
fn finite_bounds(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        })
}

/// Data range `[x0, x1, y0, y1]` grown to the aspect ratio of a `pw x ph` pixel area (equal
/// axis scales).
fn equal_scale(r: [f64; 4], pw: f64, ph: f64) -> [f64; 4] {
    let (cx, cy) = (0.5 * (r[0] + r[1]), 0.5 * (r[2] + r[3]));
    let scale = ((r[1] - r[0]) / pw).max((r[3] - r[2]) / ph).max(1e-9);
    [
        cx - 0.5 * scale * pw,
        cx + 0.5 * scale * pw,
        cy - 0.5 * scale * ph,
        cy + 0.5 * scale * ph,
    ]
}

/// Layout of a map figure (pixels).
const MAP_W: u32 = 1100;
const MAP_H: u32 = 900;
const BAR_W: u32 = 150;
const MARGIN: u32 = 20;
const Y_LABEL: u32 = 80;
const X_LABEL: u32 = 60;
const CAPTION: u32 = 50;

fn plot_area() -> (f64, f64) {
    (
        (MAP_W - BAR_W - 2 * MARGIN - Y_LABEL) as f64,
        (MAP_H - 2 * MARGIN - X_LABEL - CAPTION) as f64,
    )
}

/// Draws the heat map, isolines and colour bar; returns the chart for overlays.
fn draw_map<'a, DB: DrawingBackend + 'a>(
    root: &'a DrawingArea<DB, Shift>,
    sc: &Scenario,
    range: [f64; 4],
    title: &str,
    raster_cells: usize,
) -> Result<
    ChartContext<
        'a,
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    String,
> {
    root.fill(&WHITE).map_err(s)?;
    let (left, right) = root.split_horizontally(MAP_W - BAR_W);
    let (pw, ph) = plot_area();
    let nx = raster_cells;
    let ny = ((raster_cells as f64) * ph / pw).round().max(2.0) as usize;
    let raster = Raster::sample(sc, range, nx, ny);
    let (vmin, vmax) = raster.range().unwrap_or((0.0, 1.0));
    let mut chart = ChartBuilder::on(&left)
        .margin(MARGIN)
        .caption(title, ("sans-serif", 26))
        .x_label_area_size(X_LABEL)
        .y_label_area_size(Y_LABEL)
        .build_cartesian_2d(range[0]..range[1], range[2]..range[3])
        .map_err(s)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x, east (m)")
        .y_desc("y, north (m)")
        .label_style(("sans-serif", 16))
        .axis_desc_style(("sans-serif", 18))
        .draw()
        .map_err(s)?;
    chart
        .draw_series(
            (0..raster.ny)
                .flat_map(|j| (0..raster.nx).map(move |i| (i, j)))
                .filter_map(|(i, j)| {
                    let v = raster.values[j * raster.nx + i]?;
                    let x = raster.x0 + i as f64 * raster.dx;
                    let y = raster.y0 + j as f64 * raster.dy;
                    let c = ViridisRGB::get_color_normalized(v, vmin, vmax);
                    Some(Rectangle::new(
                        [(x, y), (x + raster.dx, y + raster.dy)],
                        c.filled(),
                    ))
                }),
        )
        .map_err(s)?;
    // Isolines: a few thin ones, the target bold.
    let level = sc.level();
    let iso = |lv: f64| {
        IsolineSegments::from_samples(
            Vec2::new(raster.x0 + 0.5 * raster.dx, raster.y0 + 0.5 * raster.dy),
            raster.dx.min(raster.dy),
            raster.nx,
            raster.ny,
            lv,
            |p| sc.field().value(0.0, p),
        )
    };
    for k in 1..=5 {
        let lv = vmin + (vmax - vmin) * k as f64 / 6.0;
        if ((lv - level) / (vmax - vmin)).abs() < 0.05 {
            continue;
        }
        let segs = iso(lv);
        chart
            .draw_series(segs.segments().iter().map(|(a, b)| {
                PathElement::new(vec![(a.x, a.y), (b.x, b.y)], WHITE.mix(0.6).stroke_width(1))
            }))
            .map_err(s)?;
    }
    let segs = iso(level);
    chart
        .draw_series(
            segs.segments().iter().map(|(a, b)| {
                PathElement::new(vec![(a.x, a.y), (b.x, b.y)], BLACK.stroke_width(3))
            }),
        )
        .map_err(s)?
        .label(format!("isoline s_d = {level}"))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(3)));
    // Colour bar.
    let units = sc
        .file()
        .field
        .units
        .clone()
        .unwrap_or_else(|| "field value".into());
    let mut bar = ChartBuilder::on(&right)
        .margin_top(MARGIN + CAPTION)
        .margin_bottom(MARGIN + X_LABEL)
        .margin_right(10)
        .y_label_area_size(90)
        .build_cartesian_2d(0.0..1.0, vmin..vmax)
        .map_err(s)?;
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc(units)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()
        .map_err(s)?;
    let n = 100;
    bar.draw_series((0..n).map(|k| {
        let a = vmin + (vmax - vmin) * k as f64 / n as f64;
        let b = vmin + (vmax - vmin) * (k + 1) as f64 / n as f64;
        Rectangle::new(
            [(0.0, a), (1.0, b)],
            ViridisRGB::get_color_normalized(0.5 * (a + b), vmin, vmax).filled(),
        )
    }))
    .map_err(s)?;
    Ok(chart)
}

fn raster_cells(format: Format) -> usize {
    match format {
        Format::Png => 220,
        Format::Svg => 70,
    }
}

/// Trajectories of one or more runs over the (first run's) field. Written to `path`.
pub fn trajectory_figure(
    runs: &[RunData],
    path: &Path,
    format: Format,
    title: &str,
) -> Result<(), PlotError> {
    let first = runs
        .first()
        .ok_or_else(|| PlotError::Input("no runs to plot".into()))?;
    let points = || runs.iter().flat_map(|r| r.trace.iter());
    let (x0, x1) = finite_bounds(points().map(|t| t.x_m));
    let (y0, y1) = finite_bounds(points().map(|t| t.y_m));
    // Both axes padded by the same 12 % of the larger extent (at least 1 m).
    let side = (x1 - x0).max(y1 - y0).max(1.0);
    let axis = |what: &str, lo: f64, hi: f64| {
        padded_axis(what, lo, hi, 0.0, 0.0).map(|r| {
            r.map(|(a, b)| {
                let pad = 0.12 * side;
                (a - pad, b + pad)
            })
        })
    };
    let no_positions = || PlotError::Data("no trace row has a finite position".into());
    let (xa, xb) = axis("x_m", x0, x1)?.ok_or_else(no_positions)?;
    let (ya, yb) = axis("y_m", y0, y1)?.ok_or_else(no_positions)?;
    let (pw, ph) = plot_area();
    let range = equal_scale([xa, xb, ya, yb], pw, ph);
    let arrow = 0.06 * (range[1] - range[0]);
    render!(path, format, (MAP_W, MAP_H), |root| {
        (|| -> DrawResult {
            let mut chart = draw_map(&root, &first.scenario, range, title, raster_cells(format))?;
            for (i, run) in runs.iter().enumerate() {
                let c = colour(i);
                chart
                    .draw_series(LineSeries::new(
                        run.trace.iter().map(|t| (t.x_m, t.y_m)),
                        c.stroke_width(2),
                    ))
                    .map_err(s)?
                    .label(run.name.clone())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3))
                    });
                let (a, b) = (run.trace[0], run.trace[run.trace.len() - 1]);
                let (hx, hy) = (a.heading_rad.cos(), a.heading_rad.sin());
                let tip = (a.x_m + arrow * hx, a.y_m + arrow * hy);
                let back = |ang: f64| {
                    let (sx, sy) = ((a.heading_rad + ang).cos(), (a.heading_rad + ang).sin());
                    (tip.0 - 0.3 * arrow * sx, tip.1 - 0.3 * arrow * sy)
                };
                chart
                    .draw_series([
                        PathElement::new(vec![(a.x_m, a.y_m), tip], c.stroke_width(3)),
                        PathElement::new(vec![back(0.45), tip, back(-0.45)], c.stroke_width(3)),
                    ])
                    .map_err(s)?;
                chart
                    .draw_series([Circle::new((a.x_m, a.y_m), 7, c.filled())])
                    .map_err(s)?;
                chart
                    .draw_series([Circle::new((a.x_m, a.y_m), 7, WHITE.stroke_width(2))])
                    .map_err(s)?;
                chart
                    .draw_series([TriangleMarker::new((b.x_m, b.y_m), 9, c.filled())])
                    .map_err(s)?;
            }
            chart
                .configure_series_labels()
                .label_font(("sans-serif", 16))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(s)?;
            Ok(())
        })()
    })
}

/// A field alone over `range` (`[x0, x1, y0, y1]`, m), with its isolines.
pub fn field_map(
    sc: &Scenario,
    range: [f64; 4],
    path: &Path,
    format: Format,
    title: &str,
) -> Result<(), PlotError> {
    let (pw, ph) = plot_area();
    let range = equal_scale(range, pw, ph);
    render!(path, format, (MAP_W, MAP_H), |root| {
        (|| -> DrawResult {
            let mut chart = draw_map(&root, sc, range, title, raster_cells(format))?;
            chart
                .configure_series_labels()
                .label_font(("sans-serif", 16))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(s)?;
            Ok(())
        })()
    })
}

/// Time series of one or more runs: the chosen panels, steady-state window shaded.
pub fn timeseries_figure(
    runs: &[RunData],
    path: &Path,
    format: Format,
    title: &str,
    panels: Panels,
) -> Result<(), PlotError> {
    let first = runs
        .first()
        .ok_or_else(|| PlotError::Input("no runs to plot".into()))?;
    type Getter = fn(&RunData) -> Vec<(f64, f64)>;
    let mut list: Vec<(&str, Getter)> = Vec::new();
    if panels.error {
        list.push(("error eps = s - s_d", |r| {
            r.trace.iter().map(|t| (t.t_s, t.error)).collect()
        }));
    }
    if panels.measurement {
        list.push(("measurement s", |r| {
            r.trace.iter().map(|t| (t.t_s, t.s)).collect()
        }));
    }
    if panels.measurement_rate {
        list.push(("measurement rate ds/dt (units/s)", |r| {
            r.trace
                .windows(2)
                .filter(|w| w[1].t_s > w[0].t_s)
                .map(|w| (w[1].t_s, (w[1].s - w[0].s) / (w[1].t_s - w[0].t_s)))
                .collect()
        }));
    }
    if panels.omega {
        list.push(("turn rate omega (rad/s)", |r| {
            r.trace.iter().map(|t| (t.t_s, t.omega_radps)).collect()
        }));
    }
    if list.is_empty() {
        return Err(PlotError::Input("no panels selected".into()));
    }
    let t_end = runs
        .iter()
        .filter_map(|r| r.trace.last().map(|t| t.t_s))
        .filter(|t| t.is_finite())
        .fold(0.0f64, f64::max)
        .max(1e-9);
    padded_axis("t_s", 0.0, t_end, 0.0, 0.0)?;
    let ss = first.steady_state_start_s();
    // Every panel's range is checked before drawing, so absurd data is a data error (not a
    // failed drawing).
    let mut ranges = Vec::with_capacity(list.len());
    for (name, get) in &list {
        let series: Vec<Vec<(f64, f64)>> = runs.iter().map(get).collect();
        let (lo, hi) = finite_bounds(series.iter().flatten().map(|p| p.1));
        ranges.push(padded_axis(name, lo, hi, 0.08, 1e-12)?.unwrap_or((-1.0, 1.0)));
    }
    let height = 80 + 300 * list.len() as u32;
    render!(path, format, (1100, height), |root| {
        (|| -> DrawResult {
            root.fill(&WHITE).map_err(s)?;
            let root = root.titled(title, ("sans-serif", 26)).map_err(s)?;
            let areas = root.split_evenly((list.len(), 1));
            for (k, ((name, get), area)) in list.iter().zip(areas.iter()).enumerate() {
                let series: Vec<Vec<(f64, f64)>> = runs.iter().map(get).collect();
                let (lo, hi) = ranges[k];
                let mut chart = ChartBuilder::on(area)
                    .margin(12)
                    .x_label_area_size(45)
                    .y_label_area_size(90)
                    .build_cartesian_2d(0.0..t_end, lo..hi)
                    .map_err(s)?;
                chart
                    .configure_mesh()
                    .x_desc("time (s)")
                    .y_desc(*name)
                    .label_style(("sans-serif", 15))
                    .axis_desc_style(("sans-serif", 16))
                    .light_line_style(WHITE.mix(0.0))
                    .draw()
                    .map_err(s)?;
                if ss > 0.0 && ss < t_end {
                    chart
                        .draw_series([Rectangle::new(
                            [(ss, lo), (t_end, hi)],
                            RGBColor(230, 230, 230).filled(),
                        )])
                        .map_err(s)?
                        .label("steady-state window")
                        .legend(|(x, y)| {
                            Rectangle::new(
                                [(x, y - 6), (x + 20, y + 6)],
                                RGBColor(220, 220, 220).filled(),
                            )
                        });
                }
                for (i, (run, pts)) in runs.iter().zip(series).enumerate() {
                    let c = colour(i);
                    chart
                        .draw_series(LineSeries::new(pts, c.stroke_width(2)))
                        .map_err(s)?
                        .label(run.name.clone())
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3))
                        });
                }
                if k == 0 {
                    chart
                        .configure_series_labels()
                        .label_font(("sans-serif", 15))
                        .background_style(WHITE.mix(0.85))
                        .border_style(BLACK)
                        .draw()
                        .map_err(s)?;
                }
            }
            Ok(())
        })()
    })
}

/// One group of a sweep summary: `(x, mean, std, n)` per distinct x, sorted by x.
pub type SummaryLine = (String, Vec<(f64, f64, f64, usize)>);

/// Reads a sweep's `results.csv` into summary lines: for each group (the `group` column's value,
/// or one group) and each distinct x, the mean, the sample standard deviation and the count of
/// the metric over the runs that have it. `x_key` is a column, or a vector key stored as columns
/// `KEY[0]`, `KEY[1]`, ... (its norm is used), or one of those columns. Also returns the runs
/// left out (no finite metric or x).
pub fn sweep_summary(
    results_csv: &Path,
    x_key: &str,
    metric: &str,
    group: Option<&str>,
) -> Result<(Vec<SummaryLine>, usize), PlotError> {
    let err = |m: String| PlotError::Data(format!("{}: {m}", results_csv.display()));
    let mut rdr = csv::Reader::from_reader(crate::open_input(results_csv)?);
    let headers = rdr.headers().map_err(|e| err(e.to_string()))?.clone();
    let names = || headers.iter().collect::<Vec<_>>().join(", ");
    let col = |n: &str| {
        headers
            .iter()
            .position(|h| h == n)
            .ok_or_else(|| err(format!("no column `{n}`; columns: {}", names())))
    };
    // x: a column, or the components of a vector key (its norm).
    let x_cols: Vec<usize> = match headers.iter().position(|h| h == x_key) {
        Some(i) => vec![i],
        None => {
            let comps: Vec<usize> = (0..)
                .map_while(|k| headers.iter().position(|h| h == format!("{x_key}[{k}]")))
                .collect();
            if comps.is_empty() {
                return Err(err(format!(
                    "no column `{x_key}` (nor `{x_key}[0]`, ...); columns: {}",
                    names()
                )));
            }
            comps
        }
    };
    let yi = col(metric)?;
    let gi = group.map(col).transpose()?;
    let mut by: std::collections::BTreeMap<String, std::collections::BTreeMap<u64, Vec<f64>>> =
        Default::default();
    let mut skipped = 0;
    for rec in rdr.records() {
        let rec = rec.map_err(|e| err(e.to_string()))?;
        let num = |i: usize| {
            rec.get(i)
                .and_then(|v| v.parse::<f64>().ok())
                .filter(|v| v.is_finite())
        };
        let x = if x_cols.len() == 1 {
            num(x_cols[0])
        } else {
            x_cols
                .iter()
                .map(|&i| num(i).map(|v| v * v))
                .sum::<Option<f64>>()
                .map(f64::sqrt)
        };
        match (x, num(yi)) {
            (Some(x), Some(y)) => {
                let g = gi.and_then(|i| rec.get(i)).unwrap_or("").to_string();
                // Keyed by the bits of x (+0.0 for -0.0): the same x value, one point.
                let key = if x == 0.0 {
                    0.0f64.to_bits()
                } else {
                    x.to_bits()
                };
                by.entry(g).or_default().entry(key).or_default().push(y);
            }
            _ => skipped += 1,
        }
    }
    if by.is_empty() {
        return Err(err(format!("no run has both `{x_key}` and `{metric}`")));
    }
    let lines = by
        .into_iter()
        .map(|(g, xs)| {
            let mut pts: Vec<(f64, f64, f64, usize)> = xs
                .into_iter()
                .map(|(k, ys)| {
                    let n = ys.len();
                    let mean = ys.iter().sum::<f64>() / n as f64;
                    let var = if n > 1 {
                        ys.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / (n - 1) as f64
                    } else {
                        0.0
                    };
                    (f64::from_bits(k), mean, var.sqrt(), n)
                })
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            (g, pts)
        })
        .collect();
    Ok((lines, skipped))
}

/// A sweep summary figure: the metric's mean against `x_key` with an error bar of one sample
/// standard deviation at each x value, one line per `group` value (README, "Sweeps").
pub fn sweep_figure(
    results_csv: &Path,
    x_key: &str,
    metric: &str,
    group: Option<&str>,
    path: &Path,
    format: Format,
) -> Result<(), PlotError> {
    let err = |m: String| PlotError::Data(format!("{}: {m}", results_csv.display()));
    let (lines, skipped) = sweep_summary(results_csv, x_key, metric, group)?;
    let all = || lines.iter().flat_map(|l| l.1.iter());
    let (x0, x1) = finite_bounds(all().map(|p| p.0));
    let (y0, _) = finite_bounds(all().map(|p| p.1 - p.2));
    let (_, y1) = finite_bounds(all().map(|p| p.1 + p.2));
    let bad = || err("no finite values".into());
    let (xa, xb) = padded_axis(x_key, x0, x1, 0.05, 1e-9)?.ok_or_else(bad)?;
    let (ya, yb) = padded_axis(metric, y0, y1, 0.08, 1e-12)?.ok_or_else(bad)?;
    let runs: usize = all().map(|p| p.3).sum();
    let title = format!(
        "{metric} against {x_key}: mean +- 1 std over {runs} runs{}",
        if skipped > 0 {
            format!(" ({skipped} without a value)")
        } else {
            String::new()
        }
    );
    // A long title gets a smaller font rather than running off the image.
    let title_px = (22.0 * 75.0 / title.chars().count().max(75) as f64).max(12.0);
    render!(path, format, (1000, 700), |root| {
        (|| -> DrawResult {
            root.fill(&WHITE).map_err(s)?;
            let mut chart = ChartBuilder::on(&root)
                .margin(20)
                .caption(&title, ("sans-serif", title_px))
                .x_label_area_size(50)
                .y_label_area_size(90)
                .build_cartesian_2d(xa..xb, ya..yb)
                .map_err(s)?;
            chart
                .configure_mesh()
                .x_desc(x_key)
                .y_desc(metric)
                .label_style(("sans-serif", 15))
                .axis_desc_style(("sans-serif", 16))
                .draw()
                .map_err(s)?;
            for (i, (g, pts)) in lines.iter().enumerate() {
                let c = colour(i + 1);
                let label = match group {
                    Some(k) => format!("{k} = {g}"),
                    None => metric.to_string(),
                };
                chart
                    .draw_series(LineSeries::new(
                        pts.iter().map(|p| (p.0, p.1)),
                        c.stroke_width(2),
                    ))
                    .map_err(s)?
                    .label(label)
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                    });
                chart
                    .draw_series(pts.iter().map(|p| {
                        ErrorBar::new_vertical(p.0, p.1 - p.2, p.1, p.1 + p.2, c.filled(), 8)
                    }))
                    .map_err(s)?;
                chart
                    .draw_series(pts.iter().map(|p| Circle::new((p.0, p.1), 4, c.filled())))
                    .map_err(s)?;
            }
            if group.is_some() {
                chart
                    .configure_series_labels()
                    .position(SeriesLabelPosition::UpperRight)
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .label_font(("sans-serif", 15))
                    .draw()
                    .map_err(s)?;
            }
            Ok(())
        })()
    })
}
