//! The figures themselves, drawn with plotters on a PNG or SVG backend.

use crate::run_data::RunData;
use crate::style::{tick_label, tick_step, value_label, Format, Style};
use crate::{fonts, PlotError};
use isotrack_core::{ScalarField, Vec2};
use isotrack_fields::isoline::IsolineSegments;
use isotrack_runs::summary::Ended;
use isotrack_scenario::Scenario;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

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

/// The most runs a legend names one by one: as many as there are colours (past them the
/// colours repeat, and a legend of a team's 10 000 vehicles ran off the figure, mem45).
const LEGEND_RUNS: usize = RUN_COLOURS.len();

/// Whether a legend of `n` runs names run `i`: every run when they are at most
/// [`LEGEND_RUNS`], else the first `LEGEND_RUNS - 1`, the last entry saying how many more
/// ([`more_runs_entry`]).
fn legend_names(i: usize, n: usize) -> bool {
    n <= LEGEND_RUNS || i + 1 < LEGEND_RUNS
}

/// The last legend entry of a figure of `n` runs when it names fewer than all
/// ([`legend_names`]): "and K more", with no line (their colours repeat the named ones').
fn more_runs_entry<'a, DB: DrawingBackend + 'a>(
    chart: &mut MapChart<'a, DB>,
    n: usize,
) -> DrawResult {
    if n > LEGEND_RUNS {
        chart
            .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())
            .map_err(s)?
            .label(format!("and {} more", n + 1 - LEGEND_RUNS))
            .legend(|(x, y)| EmptyElement::at((x, y)));
    }
    Ok(())
}

type DrawResult = Result<(), String>;

fn s<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// Draws a figure into a fresh temporary file beside `path` (same extension, so the encoder
/// picks the same format; created by `isotrack_runs::files::create_output`), then renames it
/// over `path`, marked as isotrack's (`mark`). An existing `path` that is not a regular file
/// (a symbolic link, a FIFO) is refused at once: never written through, never waited on.
pub(crate) fn draw_atomic(path: &Path, body: impl FnOnce(&Path) -> DrawResult) -> DrawResult {
    isotrack_runs::files::refuse_non_regular(path).map_err(s)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.{}.tmp{ext}", std::process::id()));
    drop(isotrack_runs::files::create_output(&tmp).map_err(s)?);
    // Removed if the command is interrupted while drawing (att38-10: Ctrl-C during `plot`
    // left `.trajectory.png.PID.tmp.png` behind); no longer once renamed into place.
    let pending = isotrack_runs::cleanup::register(&tmp);
    // Every figure carries isotrack's mark (att38-9): a later plot tells it from the user's
    // file of that name.
    let res = body(&tmp)
        .and_then(|()| crate::mark::mark(&tmp))
        .and_then(|()| std::fs::rename(&tmp, path).map_err(s));
    drop(pending);
    if res.is_err() {
        let _ = std::fs::remove_file(&tmp);
        if isotrack_runs::cleanup::exiting() {
            // An interrupt removed the temporary under the drawing and ends the process (exit
            // 130): no error of its making is printed (att48-1).
            isotrack_runs::cleanup::wait_for_exit();
        }
    }
    res
}

/// Runs a drawing body on a PNG or a SVG backend of the given size, then writes the file
/// ([`draw_atomic`]).
macro_rules! render {
    ($path:expr, $format:expr, $size:expr, |$root:ident| $body:expr) => {{
        fonts();
        let path: &Path = $path;
        let res: DrawResult = draw_atomic(path, |tmp| match $format {
            Format::Png => {
                let $root =
                    crate::bitmap::SafeLines(BitMapBackend::new(tmp, $size)).into_drawing_area();
                $body.and_then(|_| $root.present().map_err(s))
            }
            Format::Svg => {
                let $root = SVGBackend::new(tmp, $size).into_drawing_area();
                $body
                    .and_then(|_| $root.present().map_err(s))
                    .and_then(|_| crate::style::svg_without_controls(tmp))
            }
        });
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
    fn sample(sc: &Scenario, range: [f64; 4], nx: usize, ny: usize, t_s: f64) -> Self {
        let dx = (range[1] - range[0]) / nx as f64;
        let dy = (range[3] - range[2]) / ny as f64;
        let mut values = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let p = Vec2::new(
                    range[0] + (i as f64 + 0.5) * dx,
                    range[2] + (j as f64 + 0.5) * dy,
                );
                values.push(sc.field().value(t_s, p));
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
    /// The level-`lv` isoline of `f` sampled at the raster's cell centres, `dx` apart along x
    /// and `dy` along y (cells need not be square: the plot area's pixels rarely divide into
    /// square cells exactly; one step `min(dx, dy)` along both axes sampled only part of the
    /// map, so the isoline stopped short of its far side along the axis of the larger step).
    fn isoline(&self, lv: f64, f: impl Fn(Vec2) -> Option<f64>) -> IsolineSegments {
        IsolineSegments::from_samples_xy(
            Vec2::new(self.x0 + 0.5 * self.dx, self.y0 + 0.5 * self.dy),
            [self.dx, self.dy],
            self.nx,
            self.ny,
            lv,
            f,
        )
    }
    /// The sample whose cell centre is nearest `p`.
    fn at(&self, p: Vec2) -> Option<f64> {
        let i = ((p.x - self.x0) / self.dx - 0.5).round();
        let j = ((p.y - self.y0) / self.dy - 0.5).round();
        if i < 0.0 || j < 0.0 || i >= self.nx as f64 || j >= self.ny as f64 {
            return None;
        }
        self.values[j as usize * self.nx + i as usize]
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

pub use crate::limits::MAX_AXIS_ABS;

/// The relative spread under which [`padded_axis`] calls data flat: a few thousand `f64` ulps,
/// far below any spread a figure could show in ticks of at most eight significant digits.
const FLAT_REL: f64 = 1e-12;

/// An axis range for data spanning `[lo, hi]` (finite values only; `None` when there are
/// none): at least `min_width` wide (and 1e-9 of its magnitude, so the ticks stay distinct in
/// `f64`), padded by `pad_frac` of its width on each side; an error naming `what` beyond
/// [`MAX_AXIS_ABS`]. Data flat at a non-zero value (equal to within [`FLAT_REL`] of their
/// magnitude: every value at the clip bound, a constant speed) get a tenth of their magnitude,
/// as matplotlib's `nonsingular` widens a flat range by 5 % each side: ticks 1e-9 of the
/// magnitude apart would need ten-digit labels that run off the figure (att49-8).
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
    let flat = hi - lo <= FLAT_REL * mag;
    let width = (hi - lo)
        .max(min_width)
        .max(if flat { 0.1 } else { 1e-9 } * mag);
    let mid = 0.5 * (lo + hi);
    let half = 0.5 * width * (1.0 + 2.0 * pad_frac);
    Ok(Some((mid - half, mid + half)))
}

/// Saturates `v` at the bound [`MAX_AXIS_ABS`], keeping its sign, when it is finite and past
/// it; whether it was. A genuine run's or sweep's number can pass the bound (att46-13: a turn
/// rate of -5.6e299 rad/s under `controller.kp = 1e300`; att49-3: that `kp` as a sweep's x
/// and a chattering of 2e301 as its metric): drawn at the bound with the axis label saying so
/// ([`clip_note`]), not refused as a data error. The one rule of every figure's axes.
fn saturate(v: &mut f64) -> bool {
    let past = v.is_finite() && v.abs() > MAX_AXIS_ABS;
    if past {
        *v = MAX_AXIS_ABS.copysign(*v);
    }
    past
}

/// An axis label `label`, with the note that values past the bound are drawn at it when
/// `clipped` ([`saturate`]).
fn clip_note(label: &str, clipped: bool) -> String {
    match clipped {
        true => format!("{label} (clipped at \u{b1}{MAX_AXIS_ABS:e})"),
        false => label.to_string(),
    }
}

/// [`saturate`] on every value of the series; whether any was.
fn saturate_values<'a>(series: impl Iterator<Item = &'a mut Vec<(f64, f64)>>) -> bool {
    series
        .flatten()
        .fold(false, |clipped, q| saturate(&mut q.1) | clipped)
}

/// A sweep summary point's error bar `(mean - std, mean + std)`, its ends (an overflowed
/// standard deviation too) held within the bound ([`saturate`]).
fn bar_ends(p: &(f64, f64, f64, usize)) -> (f64, f64) {
    let end = |v: f64| v.clamp(-MAX_AXIS_ABS, MAX_AXIS_ABS);
    (end(p.1 - p.2), end(p.1 + p.2))
}

/// [`saturate`] on a sweep summary's x values and means; whether any x was, and whether any
/// mean or error bar end was ([`bar_ends`]).
fn saturate_summary(lines: &mut [SummaryLine]) -> (bool, bool) {
    let (mut x_clipped, mut y_clipped) = (false, false);
    for p in lines.iter_mut().flat_map(|l| l.1.iter_mut()) {
        let bar_past = p.1 - p.2 < -MAX_AXIS_ABS || p.1 + p.2 > MAX_AXIS_ABS;
        x_clipped |= saturate(&mut p.0);
        y_clipped |= saturate(&mut p.1) | bar_past;
    }
    (x_clipped, y_clipped)
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

/// Layout of a map figure, in output pixels, from its size and font.
struct MapLayout {
    w: u32,
    h: u32,
    /// The colour bar's part of the width: a half-font gap, `bar_label`, the bar, a margin.
    bar_w: u32,
    /// The colour bar's label area (its tick labels and unit), right of the bar.
    bar_label: u32,
    margin: u32,
    right_pad: u32,
    y_label: u32,
    x_label: u32,
    caption: u32,
}

/// Tick labels on the colour bar, at most (plotters' default for an axis).
const BAR_LABELS: usize = 11;

/// Longest tick mark plotters draws, px (5 % of the plotting area's smaller side, at most
/// 5 px: on the narrow bar about 1 px). Labels end two tick lengths from the axis.
const BAR_TICK_PX: u32 = 5;

/// The colour bar's unit: the field's `units`, else "field value".
fn bar_units(sc: &Scenario) -> String {
    sc.file()
        .field
        .units
        .clone()
        .unwrap_or_else(|| "field value".into())
}

/// Width the colour bar's label area needs for values `[vmin, vmax]`, px: the unit's text
/// height (it is drawn rotated, at the area's right edge), a gap, the widest tick label as
/// measured in its font, and two of the longest tick marks (plotters leaves two tick lengths
/// between a label and its axis); at least the default 4.6 font sizes.
fn bar_label_width(st: &Style, units: &str, vmin: f64, vmax: f64) -> u32 {
    use plotters::coord::ranged1d::Ranged;
    use plotters::coord::types::RangedCoordf64;
    let f = st.base_font();
    let vs = tick_step(vmin, vmax, 10);
    let label_font = FontDesc::from(st.font(0.9));
    let widest = RangedCoordf64::from(vmin..vmax)
        .key_points(BAR_LABELS)
        .iter()
        .filter_map(|v| label_font.box_size(&tick_label(*v, vs)).ok())
        .map(|(w, _)| w)
        .max()
        .unwrap_or(0);
    let desc = FontDesc::from(st.font(1.0))
        .box_size(units)
        .map_or(0, |(_, h)| h);
    let need = desc + (0.4 * f) as u32 + widest + 2 * BAR_TICK_PX;
    need.max((4.6 * f) as u32)
}

impl MapLayout {
    fn new(st: &Style, title: &str) -> Self {
        let (w, h) = st.size((1100, 900), (560, 460));
        let f = st.base_font();
        Self {
            w,
            h,
            bar_w: (0.03 * w as f64 + 8.0 * f) as u32,
            bar_label: (4.6 * f) as u32,
            margin: f.round() as u32,
            // Room for the last x tick label, which centres on the plot's right edge.
            right_pad: (1.5 * f) as u32,
            y_label: (4.8 * f) as u32,
            x_label: (3.4 * f) as u32,
            caption: if title.is_empty() {
                0
            } else {
                (2.4 * f) as u32
            },
        }
    }
    /// The bar's right margin: what the bar's part of the width leaves after the half-font gap,
    /// the label area and the 1.6-font-wide bar.
    fn bar_right(&self, f: f64, bar_label: u32) -> u32 {
        self.bar_w
            .saturating_sub(bar_label + (1.6 * f) as u32 + (0.5 * f) as u32)
    }

    /// Makes room for the colour bar's tick labels of `sc` over `range` at the times `at_s`
    /// (sampled coarsely: the map's own samples are finer, so [`draw_map`] measures again):
    /// a wider label area takes the bar's right margin first (down to half a font size), then
    /// width from the map. Unchanged when the labels fit the default.
    fn fit_bar_labels(&mut self, st: &Style, sc: &Scenario, range: [f64; 4], at_s: &[f64]) {
        let units = bar_units(sc);
        let need = at_s
            .iter()
            .filter_map(|&t| Raster::sample(sc, range, 48, 48, t).range())
            .map(|(lo, hi)| bar_label_width(st, &units, lo, hi))
            .max()
            .unwrap_or(0);
        if need > self.bar_label {
            let f = st.base_font();
            let spare = self
                .bar_right(f, self.bar_label)
                .saturating_sub((0.5 * f) as u32);
            let extra = need - self.bar_label;
            self.bar_w += extra.saturating_sub(spare);
            self.bar_label = need;
        }
    }

    /// The plotting area, pixels.
    fn plot_area(&self) -> (f64, f64) {
        let w =
            self.w as f64 - (self.bar_w + 2 * self.margin + self.right_pad + self.y_label) as f64;
        let h = self.h as f64 - (2 * self.margin + self.x_label + self.caption) as f64;
        (w.max(50.0), h.max(50.0))
    }
}

/// The layout of a map of `sc` over the data range `data` (`[x0, x1, y0, y1]`, m), its colour
/// bar sized for the field at the times `at_s`, and the range grown to the plotting area's
/// aspect ratio (equal scales).
fn map_layout(
    st: &Style,
    title: &str,
    sc: &Scenario,
    data: [f64; 4],
    at_s: &[f64],
) -> (MapLayout, [f64; 4]) {
    let mut lay = MapLayout::new(st, title);
    let (pw, ph) = lay.plot_area();
    lay.fit_bar_labels(st, sc, equal_scale(data, pw, ph), at_s);
    let (pw, ph) = lay.plot_area();
    (lay, equal_scale(data, pw, ph))
}

/// Where a legend goes: the corner of `range` holding the fewest of `points`, so it covers as
/// little data as it can.
fn emptiest_corner(
    points: impl Iterator<Item = (f64, f64)>,
    range: [f64; 4],
) -> SeriesLabelPosition {
    let (mx, my) = (0.5 * (range[0] + range[1]), 0.5 * (range[2] + range[3]));
    // [upper left, upper right, lower left, lower right]
    let mut n = [0usize; 4];
    for (x, y) in points {
        if x.is_finite() && y.is_finite() {
            n[usize::from(y < my) * 2 + usize::from(x >= mx)] += 1;
        }
    }
    // Upper right first on a tie (the usual place).
    let order = [1usize, 0, 3, 2];
    let best = order.iter().copied().min_by_key(|&i| n[i]).unwrap_or(1);
    match best {
        0 => SeriesLabelPosition::UpperLeft,
        1 => SeriesLabelPosition::UpperRight,
        2 => SeriesLabelPosition::LowerLeft,
        _ => SeriesLabelPosition::LowerRight,
    }
}

type MapChart<'a, DB> = ChartContext<
    'a,
    DB,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// When a map is drawn: the time of its heat map and bold target isoline, and earlier times
/// whose target isolines are drawn too (a field that moves: coloured from light, earliest, to
/// dark).
#[derive(Clone, Debug, Default)]
struct MapTimes {
    at_s: f64,
    earlier_s: Vec<f64>,
}

impl MapTimes {
    /// For a scenario and the end of its run: the field at the end, and for a field that moves
    /// its isolines at 0, 1/5, ..., 4/5 of the run.
    fn for_run(sc: &Scenario, t_end_s: f64) -> Self {
        if sc.is_time_varying() && t_end_s > 0.0 {
            Self {
                at_s: t_end_s,
                earlier_s: (0..5).map(|k| t_end_s * k as f64 / 5.0).collect(),
            }
        } else {
            Self::default()
        }
    }
}

/// Draws the heat map (one raster image, in SVG too), the isolines and the colour bar; returns
/// the chart for overlays.
fn draw_map<'a, DB: DrawingBackend + 'a>(
    root: &'a DrawingArea<DB, Shift>,
    sc: &Scenario,
    range: [f64; 4],
    (title, lay): (&str, &MapLayout),
    st: &Style,
    times: &MapTimes,
) -> Result<MapChart<'a, DB>, String> {
    root.fill(&WHITE).map_err(s)?;
    let (left, right) = root.split_horizontally(lay.w - lay.bar_w);
    let mut chart = ChartBuilder::on(&left)
        .margin(lay.margin)
        .margin_right(lay.margin + lay.right_pad)
        .caption(title, st.font(1.6))
        .x_label_area_size(lay.x_label)
        .y_label_area_size(lay.y_label)
        .build_cartesian_2d(range[0]..range[1], range[2]..range[3])
        .map_err(s)?;
    let (xs, ys) = (
        tick_step(range[0], range[1], 10),
        tick_step(range[2], range[3], 10),
    );
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x, east (m)")
        .y_desc("y, north (m)")
        .x_label_formatter(&|v| tick_label(*v, xs))
        .y_label_formatter(&|v| tick_label(*v, ys))
        .label_style(st.font(1.0))
        .axis_desc_style(st.font(1.1))
        .draw()
        .map_err(s)?;
    // The raster: one value per `cell` pixels, drawn as one image (an SVG used to hold 5 000
    // rectangles, most of a megabyte).
    let (pw, ph) = chart.plotting_area().dim_in_pixel();
    let cell = match st.format {
        Format::Png => 2,
        Format::Svg => 3,
    };
    let (nx, ny) = ((pw / cell).max(2) as usize, (ph / cell).max(2) as usize);
    let raster = Raster::sample(sc, range, nx, ny, times.at_s);
    let (vmin, vmax) = raster.range().unwrap_or((0.0, 1.0));
    let mut buf = vec![255u8; (pw * ph * 3) as usize];
    for py in 0..ph {
        // Image row 0 is the top (north) edge; raster row 0 the south.
        let j = ((ph - 1 - py) as usize * ny / ph as usize).min(ny - 1);
        for px in 0..pw {
            let i = (px as usize * nx / pw as usize).min(nx - 1);
            if let Some(v) = raster.values[j * nx + i] {
                let c = st.colormap.colour(v, vmin, vmax);
                let o = ((py * pw + px) * 3) as usize;
                buf[o..o + 3].copy_from_slice(&[c.0, c.1, c.2]);
            }
        }
    }
    if let Some(img) = BitMapElement::with_owned_buffer((range[0], range[3]), (pw, ph), buf) {
        chart.draw_series(std::iter::once(img)).map_err(s)?;
    }
    draw_isolines(&mut chart, sc, &raster, (vmin, vmax), st, times)?;
    draw_colour_bar(&right, sc, lay, st, (vmin, vmax))?;
    Ok(chart)
}

/// The map's isolines over its raster: a few thin ones, the target bold, and for a field that
/// moves the target at earlier times, light (early) to dark.
fn draw_isolines<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    sc: &Scenario,
    raster: &Raster,
    (vmin, vmax): (f64, f64),
    st: &Style,
    times: &MapTimes,
) -> DrawResult {
    // Isolines: a few thin ones, the target bold.
    let level = sc.level();
    let iso_at = |lv: f64, t: f64| raster.isoline(lv, |p| sc.field().value(t, p));
    // At the map's own time the raster's values are the samples (no second evaluation).
    let iso = |lv: f64| raster.isoline(lv, |p| raster.at(p));
    // A field that moves: the target isoline at earlier times, light (early) to dark.
    let n_earlier = times.earlier_s.len();
    for (k, &t) in times.earlier_s.iter().enumerate() {
        let shade = (200.0 - 150.0 * k as f64 / n_earlier.max(1) as f64) as u8;
        let c = RGBColor(shade, shade, 255);
        let w = st.px(2.0);
        chart
            .draw_series(iso_at(level, t).segments().iter().map(move |(a, b)| {
                PathElement::new(vec![(a.x, a.y), (b.x, b.y)], c.stroke_width(w))
            }))
            .map_err(s)?
            .label(format!("isoline at t = {} s", tick_label(t, 1.0)))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(w)));
    }
    for k in 1..=5 {
        let lv = vmin + (vmax - vmin) * k as f64 / 6.0;
        if ((lv - level) / (vmax - vmin)).abs() < 0.05 {
            continue;
        }
        let segs = iso(lv);
        chart
            .draw_series(segs.segments().iter().map(|(a, b)| {
                PathElement::new(
                    vec![(a.x, a.y), (b.x, b.y)],
                    WHITE.mix(0.6).stroke_width(st.px(1.0)),
                )
            }))
            .map_err(s)?;
    }
    let segs = iso(level);
    let bold = st.px(3.0);
    chart
        .draw_series(
            segs.segments().iter().map(|(a, b)| {
                PathElement::new(vec![(a.x, a.y), (b.x, b.y)], BLACK.stroke_width(bold))
            }),
        )
        .map_err(s)?
        .label(if n_earlier > 0 {
            format!(
                "isoline s_d = {} at t = {} s",
                value_label(level),
                tick_label(times.at_s, 1.0)
            )
        } else {
            format!("isoline s_d = {}", value_label(level))
        })
        .legend(move |(x, y)| {
            PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(bold))
        });
    Ok(())
}

/// The map's colour bar on `right`, over `[vmin, vmax]`: the bar, its tick marks and tick
/// labels to its right, each label starting two tick lengths right of the bar (left-aligned,
/// so a label is never drawn under the bar however the PNG renderer measures its text:
/// nu36-1, right-aligned labels left of the bar lost their last digits under it in PNG), and
/// the unit, rotated, right of the labels.
fn draw_colour_bar<DB: DrawingBackend>(
    right: &DrawingArea<DB, Shift>,
    sc: &Scenario,
    lay: &MapLayout,
    st: &Style,
    (vmin, vmax): (f64, f64),
) -> DrawResult {
    use plotters::coord::ranged1d::Ranged;
    use plotters::coord::types::RangedCoordf64;
    // Colour bar, its ticks as fine as the field's span needs (a nearly flat field still gets
    // distinct labels).
    let units = bar_units(sc);
    // The bar 1.6 font sizes wide, its labels and unit to its right, as wide as the labels
    // measure (more than the layout planned pushes the bar's right margin in).
    let f = st.base_font();
    let bar_label = lay.bar_label.max(bar_label_width(st, &units, vmin, vmax));
    let bar_right = lay.bar_right(f, bar_label);
    let mut bar = ChartBuilder::on(right)
        .margin_top(lay.margin + lay.caption)
        .margin_bottom(lay.margin + lay.x_label)
        .margin_left((0.5 * f) as u32)
        .margin_right(bar_right)
        .right_y_label_area_size(bar_label)
        .build_cartesian_2d(0.0..1.0, vmin..vmax)
        .map_err(s)?;
    let vs = tick_step(vmin, vmax, 10);
    // The mesh draws the tick marks and the unit; the labels are drawn below, left-aligned.
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_labels(BAR_LABELS)
        .y_desc(units)
        .y_label_formatter(&|_| String::new())
        .label_style(st.font(0.9))
        .axis_desc_style(st.font(1.0))
        .draw()
        .map_err(s)?;
    let n = 100;
    bar.draw_series((0..n).map(|k| {
        let a = vmin + (vmax - vmin) * k as f64 / n as f64;
        let b = vmin + (vmax - vmin) * (k + 1) as f64 / n as f64;
        Rectangle::new(
            [(0.0, a), (1.0, b)],
            st.colormap.colour(0.5 * (a + b), vmin, vmax).filled(),
        )
    }))
    .map_err(s)?;
    let (x0, y0) = right.get_base_pixel();
    let style = TextStyle::from(st.font(0.9)).pos(plotters::style::text_anchor::Pos::new(
        plotters::style::text_anchor::HPos::Left,
        plotters::style::text_anchor::VPos::Center,
    ));
    for v in RangedCoordf64::from(vmin..vmax).key_points(BAR_LABELS) {
        let (x, y) = bar.backend_coord(&(1.0, v));
        right
            .draw_text(
                &tick_label(v, vs),
                &style,
                (x - x0 + 1 + 2 * BAR_TICK_PX as i32, y - y0),
            )
            .map_err(s)?;
    }
    Ok(())
}

/// Trajectories of one or more runs over their field (one field: runs over different fields,
/// see [`crate::same_field`], are a [`PlotError::Data`]). Written to `path`.
pub fn trajectory_figure(
    runs: &[RunData],
    path: &Path,
    st: &Style,
    title: &str,
) -> Result<(), PlotError> {
    let title = st.title(title);
    let first = runs
        .first()
        .ok_or_else(|| PlotError::Input("no runs to plot".into()))?;
    // One field is drawn under every path: runs over different fields are refused.
    crate::same_field(runs)?;
    let points = || runs.iter().flat_map(|r| r.trace.iter());
    let extent = paths_extent(runs)?;
    let t_end = first.trace.last().map_or(0.0, |t| t.t_s);
    let times = MapTimes::for_run(&first.scenario, t_end);
    let (lay, range) = map_layout(st, title, &first.scenario, extent, &[times.at_s]);
    let arrow = 0.06 * (range[1] - range[0]);
    let legend_at = emptiest_corner(points().map(|t| (t.x_m, t.y_m)), range);
    render!(path, st.format, (lay.w, lay.h), |root| {
        (|| -> DrawResult {
            let mut chart = draw_map(&root, &first.scenario, range, (title, &lay), st, &times)?;
            let marks = PathMarks::of(runs.len(), st);
            for (i, run) in runs.iter().enumerate() {
                let named = legend_names(i, runs.len());
                draw_path(&mut chart, run, (colour(i), named), arrow, &marks, st)?;
            }
            more_runs_entry(&mut chart, runs.len())?;
            chart
                .configure_series_labels()
                .label_font(st.font(1.0))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(legend_at)
                .draw()
                .map_err(s)?;
            Ok(())
        })()
    })
}

/// The map's extent `[x0, x1, y0, y1]` (m) around the finite positions of `runs`' traces:
/// both axes padded by the same 12 % of the larger extent (at least 1 m).
fn paths_extent(runs: &[RunData]) -> Result<[f64; 4], PlotError> {
    let points = || runs.iter().flat_map(|r| r.trace.iter());
    let (x0, x1) = finite_bounds(points().map(|t| t.x_m));
    let (y0, y1) = finite_bounds(points().map(|t| t.y_m));
    let pad = 0.12 * (x1 - x0).max(y1 - y0).max(1.0);
    let no_positions = || PlotError::Data("no trace row has a finite position".into());
    let (xa, xb) = padded_axis("x_m", x0, x1, 0.0, 0.0)?.ok_or_else(no_positions)?;
    let (ya, yb) = padded_axis("y_m", y0, y1, 0.0, 0.0)?.ok_or_else(no_positions)?;
    Ok([xa - pad, xb + pad, ya - pad, yb + pad])
}

/// Paths up to which each has its full start and end marks on the trajectory figure: an
/// arrow along its first heading, a dot in a white ring at its start (7 px), a triangle at its
/// end (9 px).
pub const FULL_MARK_PATHS: usize = 16;

/// The start and end marks of each of `n` paths on the trajectory figure ([`draw_path`]).
/// Up to [`FULL_MARK_PATHS`] paths, the full marks. Beyond, the marks of all the paths cover
/// no more than those of [`FULL_MARK_PATHS`] full ones: each mark's radius shrinks by
/// `sqrt(FULL_MARK_PATHS / n)` (its area by `FULL_MARK_PATHS / n`), without the white ring
/// and the arrow (att46-17: 5000 rings of 7 px round starts along a 6.93 m circle made a white
/// band over the isoline and every track); a mark below one output pixel is left out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathMarks {
    /// The start dot's radius, output px (`None`: no start dot).
    pub start_px: Option<u32>,
    /// The end triangle's size, output px (`None`: no end triangle).
    pub end_px: Option<u32>,
    /// Whether the start dot has its white ring.
    pub ring: bool,
    /// Whether the path has its heading arrow.
    pub arrow: bool,
}

impl PathMarks {
    /// The marks of each of `n` paths drawn in style `st`.
    pub fn of(n: usize, st: &Style) -> Self {
        let full = n <= FULL_MARK_PATHS;
        let shrink = if full {
            1.0
        } else {
            (FULL_MARK_PATHS as f64 / n as f64).sqrt()
        };
        let size = |px: f64| {
            let out = px * shrink * st.k();
            (out >= 1.0).then(|| out.round() as u32)
        };
        PathMarks {
            start_px: if full { Some(st.px(7.0)) } else { size(7.0) },
            end_px: if full { Some(st.px(9.0)) } else { size(9.0) },
            ring: full,
            arrow: full,
        }
    }
}

/// One run's path on the trajectory figure in colour `c`, labelled with its name for the
/// legend when `named` ([`legend_names`]): the line through its finite positions, and as
/// `marks` says ([`PathMarks`]) an arrow `arrow` (m) long along its first heading, a dot in a
/// ring at its start and a triangle at its end.
fn draw_path<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    run: &RunData,
    (c, named): (RGBColor, bool),
    arrow: f64,
    marks: &PathMarks,
    st: &Style,
) -> DrawResult {
    let (w2, w3) = (st.px(2.0), st.px(3.0));
    let line = chart
        .draw_series(LineSeries::new(
            run.trace
                .iter()
                .filter(|t| t.x_m.is_finite() && t.y_m.is_finite())
                .map(|t| (t.x_m, t.y_m)),
            c.stroke_width(w2),
        ))
        .map_err(s)?;
    if named {
        line.label(run.name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(w3)));
    }
    let (a, b) = (run.trace[0], run.trace[run.trace.len() - 1]);
    if marks.arrow {
        let (hx, hy) = (a.heading_rad.cos(), a.heading_rad.sin());
        let tip = (a.x_m + arrow * hx, a.y_m + arrow * hy);
        let back = |ang: f64| {
            let (sx, sy) = ((a.heading_rad + ang).cos(), (a.heading_rad + ang).sin());
            (tip.0 - 0.3 * arrow * sx, tip.1 - 0.3 * arrow * sy)
        };
        chart
            .draw_series([
                PathElement::new(vec![(a.x_m, a.y_m), tip], c.stroke_width(w3)),
                PathElement::new(vec![back(0.45), tip, back(-0.45)], c.stroke_width(w3)),
            ])
            .map_err(s)?;
    }
    if let Some(r) = marks.start_px {
        chart
            .draw_series([Circle::new((a.x_m, a.y_m), r, c.filled())])
            .map_err(s)?;
        if marks.ring {
            chart
                .draw_series([Circle::new((a.x_m, a.y_m), r, WHITE.stroke_width(w2))])
                .map_err(s)?;
        }
    }
    if let Some(e) = marks.end_px {
        chart
            .draw_series([TriangleMarker::new((b.x_m, b.y_m), e, c.filled())])
            .map_err(s)?;
    }
    Ok(())
}

/// An animated GIF of one run over time: at each of `frames` times through the run, the field
/// (heat map and target isoline at that time: a field that moves is seen moving), the path so
/// far and the vehicle. `delay_ms` between frames.
pub fn animation_gif(
    run: &RunData,
    path: &Path,
    st: &Style,
    title: &str,
    frames: usize,
    delay_ms: u32,
) -> Result<(), PlotError> {
    animation_gif_team(std::slice::from_ref(run), path, st, title, frames, delay_ms)
}

/// [`animation_gif`] of several vehicles at once (a team's, [`RunData::load_team`]): every
/// vehicle's path so far and position in its own colour (the trajectory figure's), on the
/// first one's field and clock. One vehicle draws exactly [`animation_gif`]'s frames.
pub fn animation_gif_team(
    runs: &[RunData],
    path: &Path,
    st: &Style,
    title: &str,
    frames: usize,
    delay_ms: u32,
) -> Result<(), PlotError> {
    let title = st.title(title);
    let run = runs
        .first()
        .ok_or_else(|| PlotError::Input("no runs to animate".into()))?;
    let tr = &run.trace;
    let extent = paths_extent(runs)?;
    let small = gif_style(st);
    let t_end = tr.last().map_or(0.0, |t| t.t_s);
    let frames = frames.clamp(1, 1000);
    // One layout for every frame: its colour bar sized for the field at the start, the middle
    // and the end.
    let (lay, range) = map_layout(
        &small,
        title,
        &run.scenario,
        extent,
        &[0.0, 0.5 * t_end, t_end],
    );
    let res: DrawResult = draw_atomic(path, |path| {
        fonts();
        let root = crate::bitmap::SafeLines(
            BitMapBackend::gif(path, (lay.w, lay.h), delay_ms).map_err(s)?,
        )
        .into_drawing_area();
        for k in 0..frames {
            let t = if frames == 1 {
                t_end
            } else {
                t_end * k as f64 / (frames - 1) as f64
            };
            let times = MapTimes {
                at_s: t,
                earlier_s: vec![],
            };
            let frame_title = format!("{title}  t = {} s", tick_label(t, 1.0));
            let mut chart = draw_map(
                &root,
                &run.scenario,
                range,
                (&frame_title, &lay),
                &small,
                &times,
            )?;
            for (i, one) in runs.iter().enumerate() {
                draw_path_until(&mut chart, one, t, colour(i), &small)?;
            }
            root.present().map_err(s)?;
        }
        Ok(())
    });
    res.map_err(|message| PlotError::Draw {
        path: path.display().to_string(),
        message,
    })
}

/// The style of a GIF frame: small, a third of the map's default pixels (and an 11 px font)
/// unless `--size` says otherwise.
fn gif_style(st: &Style) -> Style {
    let mut small = st.clone();
    if small.size_px.is_none() {
        small.size_px = Some((660, 540));
        small.font_px = Some(small.font_px.unwrap_or(11.0));
    }
    small
}

/// One vehicle on an animation frame at time `t` (s), in colour `c`: its path so far (the
/// finite positions up to `t`) and a dot where it is.
fn draw_path_until<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    run: &RunData,
    t: f64,
    c: RGBColor,
    st: &Style,
) -> DrawResult {
    let upto: Vec<(f64, f64)> = run
        .trace
        .iter()
        .take_while(|r| r.t_s <= t)
        .filter(|r| r.x_m.is_finite() && r.y_m.is_finite())
        .map(|r| (r.x_m, r.y_m))
        .collect();
    chart
        .draw_series(LineSeries::new(
            upto.iter().copied(),
            c.stroke_width(st.px(2.0)),
        ))
        .map_err(s)?;
    if let Some(&last) = upto.last() {
        chart
            .draw_series([Circle::new(last, st.px(5.0), c.filled())])
            .map_err(s)?;
    }
    Ok(())
}

/// A field alone over `range` (`[x0, x1, y0, y1]`, m), with its isolines.
pub fn field_map(
    sc: &Scenario,
    range: [f64; 4],
    path: &Path,
    st: &Style,
    title: &str,
) -> Result<(), PlotError> {
    let title = st.title(title);
    let (lay, range) = map_layout(st, title, sc, range, &[0.0]);
    render!(path, st.format, (lay.w, lay.h), |root| {
        (|| -> DrawResult {
            let mut chart = draw_map(&root, sc, range, (title, &lay), st, &MapTimes::default())?;
            chart
                .configure_series_labels()
                .label_font(st.font(1.0))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(s)?;
            Ok(())
        })()
    })
}

/// `(t, value)` points of one line.
type Series = Vec<(f64, f64)>;

/// One time-series panel: its axis label and its series per run (the second, when present, is
/// drawn thin and light: the measured value under the true one).
struct Panel {
    label: &'static str,
    series: fn(&RunData) -> [Series; 2],
}

/// Whether a run's measurements differ from the true values (noise or delay): then the
/// measured value is drawn too.
fn measured_differs(r: &RunData) -> bool {
    r.trace.iter().any(|t| {
        t.s_measured
            .is_some_and(|m| (m - t.s).abs() > 1e-12 * t.s.abs().max(1.0))
    })
}

/// The panels of [`timeseries_figure`] `panels` selects, in their order (the measurement's
/// says whether any run's measured values differ from the true ones).
fn selected_panels(runs: &[RunData], panels: Panels) -> Vec<Panel> {
    let mut list: Vec<Panel> = Vec::new();
    if panels.error {
        list.push(Panel {
            label: "error \u{3b5} = s \u{2212} s_d",
            series: |r| [r.trace.iter().map(|t| (t.t_s, t.error)).collect(), vec![]],
        });
    }
    if panels.measurement {
        let noisy = runs.iter().any(measured_differs);
        // A flight's `s` is what its sensor measured: no true value is known in flight
        // (docs/FLYING.md), nu-13.
        let flights = runs
            .iter()
            .filter(|r| matches!(r.summary.ended, Ended::Flight(_)))
            .count();
        list.push(Panel {
            label: if flights == runs.len() {
                "measured field value s (flight)"
            } else if flights > 0 {
                "s: true (simulated runs), measured (flights)"
            } else if noisy {
                "s: true (bold), measured (light)"
            } else {
                "true field value s"
            },
            series: |r| {
                let truth = r.trace.iter().map(|t| (t.t_s, t.s)).collect();
                let measured = if measured_differs(r) {
                    r.trace
                        .iter()
                        .filter_map(|t| t.s_measured.map(|m| (t.t_s, m)))
                        .collect()
                } else {
                    vec![]
                };
                [truth, measured]
            },
        });
    }
    if panels.measurement_rate {
        list.push(Panel {
            label: "ds/dt (units/s)",
            series: |r| {
                let rate = r
                    .trace
                    .windows(2)
                    .filter(|w| w[1].t_s > w[0].t_s)
                    .map(|w| (w[1].t_s, (w[1].s - w[0].s) / (w[1].t_s - w[0].t_s)))
                    .collect();
                [rate, vec![]]
            },
        });
    }
    if panels.omega {
        list.push(Panel {
            label: "turn rate \u{3c9} (rad/s)",
            series: |r| {
                [
                    r.trace.iter().map(|t| (t.t_s, t.omega_radps)).collect(),
                    vec![],
                ]
            },
        });
    }
    list
}

/// Time series of one or more runs: the chosen panels, steady-state window shaded.
pub fn timeseries_figure(
    runs: &[RunData],
    path: &Path,
    st: &Style,
    title: &str,
    panels: Panels,
) -> Result<(), PlotError> {
    let title = st.title(title);
    let first = runs
        .first()
        .ok_or_else(|| PlotError::Input("no runs to plot".into()))?;
    let list = selected_panels(runs, panels);
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
    let mut data = Vec::with_capacity(list.len());
    for p in &list {
        let mut series: Vec<[Vec<(f64, f64)>; 2]> = runs.iter().map(p.series).collect();
        let label = clip_note(p.label, saturate_values(series.iter_mut().flatten()));
        let (lo, hi) = finite_bounds(series.iter().flatten().flatten().map(|q| q.1));
        let range = padded_axis(p.label, lo, hi, 0.08, 1e-12)?.unwrap_or((-1.0, 1.0));
        data.push((series, range, label));
    }
    let n = list.len() as u32;
    let (w, h) = match st.size_px {
        Some(_) => st.size((1100, 980), (560, 520)),
        None => st.size((1100, 80 + 300 * n), (560, 40 + 160 * n)),
    };
    let ts = tick_step(0.0, t_end, 10);
    render!(path, st.format, (w, h), |root| {
        (|| -> DrawResult {
            root.fill(&WHITE).map_err(s)?;
            let body = if title.is_empty() {
                root.clone()
            } else {
                root.titled(title, st.font(1.6)).map_err(s)?
            };
            let areas = body.split_evenly((list.len(), 1));
            for (k, ((series, (lo, hi), label), area)) in data.iter().zip(areas.iter()).enumerate()
            {
                let (lo, hi) = (*lo, *hi);
                let ys = tick_step(lo, hi, 8);
                let mut chart = panel_axes(
                    area,
                    st,
                    ((0.0, t_end), (lo, hi)),
                    ("time (s)", label.as_str()),
                    (ts, ys),
                )?;
                draw_time_series(&mut chart, st, runs, series, (lo, hi), (ss, t_end))?;
                if k == 0 {
                    let pts = series.iter().flat_map(|sr| sr[0].iter().copied());
                    panel_legend(&mut chart, st, emptiest_corner(pts, [0.0, t_end, lo, hi]))?;
                }
            }
            Ok(())
        })()
    })
}

/// One panel of [`timeseries_figure`] drawn: the steady-state window `[ss, t_end]` shaded,
/// then each run's series (its light second one, if any, under its main one), the values
/// outside `[lo, hi]` left out.
fn draw_time_series<'a, DB: DrawingBackend + 'a>(
    chart: &mut MapChart<'a, DB>,
    st: &Style,
    runs: &[RunData],
    series: &[[Series; 2]],
    (lo, hi): (f64, f64),
    (ss, t_end): (f64, f64),
) -> DrawResult {
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
    let (w1, w2, w3) = (st.px(1.0), st.px(2.0), st.px(3.0));
    // Values outside the panel (a non-finite row) are left out, never drawn over the
    // neighbouring panel.
    let inside = move |q: &&(f64, f64)| q.1.is_finite() && q.1 >= lo && q.1 <= hi;
    for (i, (run, [main, extra])) in runs.iter().zip(series).enumerate() {
        let c = colour(i);
        if !extra.is_empty() {
            chart
                .draw_series(LineSeries::new(
                    extra.iter().filter(inside).copied(),
                    c.mix(0.4).stroke_width(w1),
                ))
                .map_err(s)?;
        }
        let line = chart
            .draw_series(LineSeries::new(
                main.iter().filter(inside).copied(),
                c.stroke_width(w2),
            ))
            .map_err(s)?;
        if legend_names(i, runs.len()) {
            line.label(run.name.clone()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(w3))
            });
        }
    }
    more_runs_entry(chart, runs.len())
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
    let (mut lines, skipped, offset) = sweep_summary_exact(results_csv, x_key, metric, group)?;
    if let Some(o) = offset {
        for (_, pts) in &mut lines {
            for p in pts.iter_mut() {
                p.0 += o as f64;
            }
        }
    }
    Ok((lines, skipped))
}

/// An x value of a sweep summary as it is grouped: a whole number written as one (a seed, a
/// count) exactly, any other number by its bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum XKey {
    Whole(i128),
    Bits(u64),
}

/// The metric's values of a sweep's runs by group and x value.
type GroupedRuns = std::collections::BTreeMap<String, std::collections::BTreeMap<XKey, Vec<f64>>>;

/// The integers an `f64` holds exactly, `2^53` (beyond, two seeds one apart are one `f64`).
const EXACT_F64_INTEGERS: i128 = 1 << 53;

/// [`sweep_summary`] with its x values exact: an x column whose numbers are all whole numbers
/// written as such (`sim.seed`, `team.count`) is grouped by its integers, not through `f64`
/// (att36-22: seeds above 2^53 one apart were one x, their runs one "mean ± std" point). When
/// one of them is beyond what an `f64` holds exactly, the points' x are relative to the
/// smallest, returned as the offset (`Some`), so that distinct integers stay distinct points.
fn sweep_summary_exact(
    results_csv: &Path,
    x_key: &str,
    metric: &str,
    group: Option<&str>,
) -> Result<(Vec<SummaryLine>, usize, Option<i128>), PlotError> {
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
    let x_cols = x_columns(&headers, x_key).ok_or_else(|| {
        err(format!(
            "no column `{x_key}` (nor `{x_key}[0]`, ...); columns: {}",
            names()
        ))
    })?;
    let yi = col(metric)?;
    let gi = group.map(col).transpose()?;
    let mut by = GroupedRuns::default();
    // A single x column of whole numbers (each finite number of it an integer as written):
    // read before grouping, so that the x of a run is never rounded.
    let whole = x_cols.len() == 1 && whole_number_column(results_csv, x_cols[0])?;
    let mut skipped = 0;
    // Which columns hold a number in some run, and a text value of the x and the metric
    // columns (for the message when no run has both as numbers, nu-20).
    let mut seen = ColumnsSeen {
        numeric: vec![false; headers.len()],
        x_text: None,
        y_text: None,
    };
    for rec in rdr.records() {
        let rec = rec.map_err(|e| err(e.to_string()))?;
        let num = |i: usize| {
            rec.get(i)
                .and_then(|v| v.parse::<f64>().ok())
                .filter(|v| v.is_finite())
        };
        seen.note(&rec, &x_cols, yi);
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
                // Keyed by the integer as written, or by the bits of x (+0.0 for -0.0): the
                // same x value, one point.
                let key = match rec.get(x_cols[0]).map(str::parse::<i128>) {
                    Some(Ok(v)) if whole => XKey::Whole(v),
                    _ if x == 0.0 => XKey::Bits(0.0f64.to_bits()),
                    _ => XKey::Bits(x.to_bits()),
                };
                by.entry(g).or_default().entry(key).or_default().push(y);
            }
            _ => skipped += 1,
        }
    }
    if by.is_empty() {
        return Err(err(seen.why_no_run(
            &headers,
            (x_key, &x_cols),
            (metric, yi),
        )));
    }
    let (lines, offset) = summary_lines(by);
    Ok((lines, skipped, offset))
}

/// What [`sweep_summary_exact`] saw of a sweep's columns, for its message when no run has a
/// number in both the x and the metric columns (nu-20).
struct ColumnsSeen {
    /// Whether each column holds a finite number in some run.
    numeric: Vec<bool>,
    /// A text value of the x columns (the first seen), if any.
    x_text: Option<String>,
    /// A text value of the metric column (the first seen), if any.
    y_text: Option<String>,
}

impl ColumnsSeen {
    /// Notes the columns of one row `rec`, the x in columns `x_cols` and the metric in `yi`.
    fn note(&mut self, rec: &csv::StringRecord, x_cols: &[usize], yi: usize) {
        for (i, n) in self.numeric.iter_mut().enumerate() {
            *n = *n
                || rec
                    .get(i)
                    .and_then(|v| v.parse::<f64>().ok())
                    .filter(|v| v.is_finite())
                    .is_some();
        }
        let text = |i: usize| {
            rec.get(i)
                .filter(|v| !v.is_empty() && v.parse::<f64>().is_err())
                .map(str::to_string)
        };
        if self.x_text.is_none() {
            self.x_text = x_cols.iter().find_map(|&i| text(i));
        }
        if self.y_text.is_none() {
            self.y_text = text(yi);
        }
    }

    /// The message when no run has both `x_key` (in columns `x_cols`) and `metric` (in
    /// column `yi`) as numbers: which of them is text, and the columns that hold numbers.
    fn why_no_run(
        &self,
        headers: &csv::StringRecord,
        (x_key, x_cols): (&str, &[usize]),
        (metric, yi): (&str, usize),
    ) -> String {
        let numeric = &self.numeric;
        let (x_text, y_text) = (&self.x_text, &self.y_text);
        let x_is_text = x_text.is_some() && !x_cols.iter().any(|&i| numeric[i]);
        let y_is_text = y_text.is_some() && !numeric[yi];
        if !x_is_text && !y_is_text {
            return format!("no run has both `{x_key}` and `{metric}`");
        }
        let mut why = Vec::new();
        if let (true, Some(v)) = (x_is_text, x_text) {
            why.push(format!(
                "`{x_key}` is text (e.g. `{}`): --x must be a numeric key (a text key such as team.spacing or controller.kind goes to --group)",
                isotrack_scenario::load::clip(v)
            ));
        }
        if let (true, Some(v)) = (y_is_text, y_text) {
            why.push(format!(
                "`{metric}` is not a number (e.g. `{}`): --metric must be a numeric column",
                isotrack_scenario::load::clip(v)
            ));
        }
        let numbers: Vec<&str> = headers
            .iter()
            .zip(numeric.iter())
            .filter(|(_, n)| **n)
            .map(|(h, _)| h)
            .collect();
        format!(
            "no run has a number in both `{x_key}` and `{metric}`: {}; the columns holding numbers: {}",
            why.join("; "),
            numbers.join(", ")
        )
    }
}

/// The summary lines of the runs grouped `by` group and x: each x's mean, standard deviation
/// and count, sorted by x; whole-number x relative to the smallest (returned) when one of them
/// is beyond `f64`'s exact integers ([`sweep_summary_exact`]).
fn summary_lines(by: GroupedRuns) -> (Vec<SummaryLine>, Option<i128>) {
    let wholes = || {
        by.values()
            .flat_map(|xs| xs.keys())
            .filter_map(|k| match k {
                XKey::Whole(v) => Some(*v),
                XKey::Bits(_) => None,
            })
    };
    let offset = wholes()
        .any(|v| v.abs() > EXACT_F64_INTEGERS)
        .then(|| wholes().min())
        .flatten();
    let lines = by
        .into_iter()
        .map(|(g, xs)| {
            let mut pts: Vec<(f64, f64, f64, usize)> = xs
                .into_iter()
                .map(|(k, ys)| {
                    let (mean, std) = mean_and_std(&ys);
                    let x = match k {
                        XKey::Whole(v) => v.saturating_sub(offset.unwrap_or(0)) as f64,
                        XKey::Bits(b) => f64::from_bits(b),
                    };
                    (x, mean, std, ys.len())
                })
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            (g, pts)
        })
        .collect();
    (lines, offset)
}

/// Whether every finite number in column `x_col` of `results_csv` is an integer as written
/// (`sim.seed`, `team.count`: [`sweep_summary_exact`] then groups by the integers).
fn whole_number_column(results_csv: &Path, x_col: usize) -> Result<bool, PlotError> {
    let err = |m: String| PlotError::Data(format!("{}: {m}", results_csv.display()));
    let mut r = csv::Reader::from_reader(crate::open_input(results_csv)?);
    for rec in r.records() {
        let rec = rec.map_err(|e| err(e.to_string()))?;
        let v = rec.get(x_col).unwrap_or("");
        if v.parse::<f64>().is_ok_and(f64::is_finite) && v.parse::<i128>().is_err() {
            return Ok(false);
        }
    }
    Ok(true)
}

/// A tick label of a sweep figure's x axis whose values are relative to `offset` (the
/// smallest of integers beyond `f64`'s exact ones, [`sweep_summary_exact`]): a whole tick as
/// the exact integer it stands for, others as `tick_label` writes offset + tick; without an
/// offset, [`tick_label`].
fn x_tick_label(v: f64, step: f64, offset: Option<i128>) -> String {
    match offset {
        Some(o) if v.is_finite() && v.fract() == 0.0 && v.abs() < 1e38 => o
            .checked_add(v as i128)
            .map_or_else(|| tick_label(o as f64 + v, step), |x| x.to_string()),
        Some(o) => tick_label(o as f64 + v, step),
        None => tick_label(v, step),
    }
}

/// The columns of the sweep summary's x: the column `x_key`, else the components `x_key[0]`,
/// `x_key[1]`, ... of a vector key (its norm is plotted); `None` when there are neither.
fn x_columns(headers: &csv::StringRecord, x_key: &str) -> Option<Vec<usize>> {
    if let Some(i) = headers.iter().position(|h| h == x_key) {
        return Some(vec![i]);
    }
    let comps: Vec<usize> = (0..)
        .map_while(|k| headers.iter().position(|h| h == format!("{x_key}[{k}]")))
        .collect();
    (!comps.is_empty()).then_some(comps)
}

/// The mean of `ys` (not empty) and their sample standard deviation (`n - 1` in the
/// denominator; 0 for one value).
fn mean_and_std(ys: &[f64]) -> (f64, f64) {
    let n = ys.len();
    let mean = ys.iter().sum::<f64>() / n as f64;
    let var = if n > 1 {
        ys.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / (n - 1) as f64
    } else {
        0.0
    };
    (mean, var.sqrt())
}

/// A sweep figure's axes: `x` and `y` the ranges drawn, `single_x` / `single_y` the one value
/// of an axis labelled by hand at the value (else `None`).
struct SweepAxes {
    x: (f64, f64),
    y: (f64, f64),
    single_x: Option<f64>,
    single_y: Option<f64>,
}

impl SweepAxes {
    /// The axes round the summary `lines` (each mean with its error bar); a data error on
    /// `results_csv` when there are no finite values.
    fn of(
        lines: &[SummaryLine],
        (x_key, metric): (&str, &str),
        results_csv: &Path,
    ) -> Result<Self, PlotError> {
        let all = || lines.iter().flat_map(|l| l.1.iter());
        let (x0, x1) = finite_bounds(all().map(|p| p.0));
        let (y0, _) = finite_bounds(all().map(|p| bar_ends(p).0));
        let (_, y1) = finite_bounds(all().map(|p| bar_ends(p).1));
        let bad = || PlotError::Data(format!("{}: no finite values", results_csv.display()));
        // One whole x value (`team.count = [5]`): an axis one unit wide round it, labelled once
        // at the value (att30n-7: an axis 2e-7 wide was labelled 4.9999997 to 5.0000002).
        // One value that is not whole (0.1, 5.5), or a metric the same in every run: an axis a
        // fifth of the value wide round it (1 round 0), labelled once, at the value, by hand
        // (att38-7: ticks 1e-9 apart ran together and past the image's edge).
        let single_x = (x0 == x1 && x0.fract() != 0.0).then_some(x0);
        let single_y = (y0 == y1 && y0.is_finite()).then_some(y0);
        let x_width = if x0 == x1 && x0.fract() == 0.0 {
            1.0
        } else if let Some(v) = single_x {
            single_value_width(v)
        } else {
            1e-9
        };
        let x = padded_axis(x_key, x0, x1, 0.05, x_width)?.ok_or_else(bad)?;
        let y_width = single_y.map_or(1e-12, single_value_width);
        let y = padded_axis(metric, y0, y1, 0.08, y_width)?.ok_or_else(bad)?;
        Ok(Self {
            x,
            y,
            single_x,
            single_y,
        })
    }
}

/// The legend label of each summary line: `group = value` with the values shortened so that
/// the legend is as wide as the plot at most (att30n-8: two absolute paths made a legend wider
/// than the image, clipped at both edges and over a point), or the metric without a group.
fn sweep_line_labels(
    lines: &[SummaryLine],
    group: Option<&str>,
    metric: &str,
    (w, h): (u32, u32),
    f: f64,
) -> Vec<String> {
    match group {
        Some(k) => {
            let room = legend_chars_that_fit(sweep_plot_px((w, h), f).0, f);
            let prefix = format!("{k} = ").chars().count();
            let values: Vec<&str> = lines.iter().map(|l| l.0.as_str()).collect();
            let short = shortened_values(&values, room.saturating_sub(prefix).max(12));
            short.into_iter().map(|v| format!("{k} = {v}")).collect()
        }
        None => lines.iter().map(|_| metric.to_string()).collect(),
    }
}

/// A sweep summary figure: the metric's mean against `x_key` with an error bar of one sample
/// standard deviation at each x value, one line per `group` value (README, "Sweeps").
pub fn sweep_figure(
    results_csv: &Path,
    x_key: &str,
    metric: &str,
    group: Option<&str>,
    path: &Path,
    st: &Style,
) -> Result<(), PlotError> {
    let (mut lines, skipped, x_offset) = sweep_summary_exact(results_csv, x_key, metric, group)?;
    let (x_clipped, y_clipped) = saturate_summary(&mut lines);
    let (x_desc, y_desc) = (clip_note(x_key, x_clipped), clip_note(metric, y_clipped));
    let all = || lines.iter().flat_map(|l| l.1.iter());
    let axes = SweepAxes::of(&lines, (x_key, metric), results_csv)?;
    let ((xa, xb), (ya, yb)) = (axes.x, axes.y);
    let runs: usize = all().map(|p| p.3).sum();
    let default_title = sweep_title(x_key, metric, runs, skipped);
    let title = st.title(&default_title);
    let (w, h) = st.size((1000, 700), (560, 400));
    let f = st.base_font();
    let title_rel = title_font_rel(title, w, f);
    let labels = sweep_line_labels(&lines, group, metric, (w, h), f);
    let (yb, legend_at) = match group {
        Some(_) => {
            let chars = labels.iter().map(|l| l.chars().count());
            let legend = legend_box_px(chars.max().unwrap_or(0), lines.len(), f);
            sweep_legend_place(&lines, [xa, xb, ya, yb], sweep_plot_px((w, h), f), legend)
        }
        None => (yb, SeriesLabelPosition::UpperRight),
    };
    let (xs, ys) = (tick_step(xa, xb, 10), tick_step(ya, yb, 8));
    let whole_x = whole_number_labels(all().map(|p| p.0), xa, xb);
    let xs = if whole_x.is_some() { 1.0 } else { xs };
    render!(path, st.format, (w, h), |root| {
        (|| -> DrawResult {
            root.fill(&WHITE).map_err(s)?;
            let x_labels =
                whole_x.map(|n| whole_x_labels_that_fit(&root, st, n, (xa, xb), x_offset, (w, h)));
            let mut chart = ChartBuilder::on(&root)
                .margin(f as u32)
                .margin_right((2.0 * f) as u32)
                .caption(title, st.font(title_rel))
                .x_label_area_size((3.2 * f) as u32)
                .y_label_area_size((5.6 * f) as u32)
                .build_cartesian_2d(xa..xb, ya..yb)
                .map_err(s)?;
            let ticks = SweepTicks {
                x_labels,
                steps: (xs, ys),
                x_offset,
            };
            draw_sweep_mesh(&mut chart, st, (&x_desc, &y_desc), &axes, &ticks)?;
            draw_single_value_labels(&root, &chart, st, &axes)?;
            for (i, ((_, pts), label)) in lines.iter().zip(&labels).enumerate() {
                draw_summary_line(&mut chart, pts, label.clone(), colour(i + 1), st)?;
            }
            if group.is_some() {
                chart
                    .configure_series_labels()
                    .position(legend_at)
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .label_font(st.font(0.95))
                    .draw()
                    .map_err(s)?;
            }
            Ok(())
        })()
    })
}

/// How many of `n` whole-number x labels fit side by side on a sweep figure of `size` drawn
/// on `root` (att30n-15: twelve seeds near 1e9 ran together): else fewer, plotters choosing
/// a step of 1, 2 or 5. The widest of the first 13 labels over `[xa, xb]` is measured.
fn whole_x_labels_that_fit<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    st: &Style,
    n: usize,
    (xa, xb): (f64, f64),
    x_offset: Option<i128>,
    size: (u32, u32),
) -> usize {
    let f = st.base_font();
    let label_style = TextStyle::from(st.font(0.95));
    let widest = (xa.ceil() as i64..=xb.floor() as i64)
        .take(13)
        .filter_map(|v| {
            root.estimate_text_size(&x_tick_label(v as f64, 1.0, x_offset), &label_style)
                .ok()
        })
        .map(|(w, _)| f64::from(w))
        .fold(0.0, f64::max);
    whole_labels_that_fit(n, widest, sweep_plot_px(size, f).0, f)
}

/// How a sweep figure's axes are labelled: at most `x_labels` x labels (`None`: plotters'
/// default), at the tick `steps` (x, y), the x values relative to `x_offset`
/// ([`x_tick_label`]).
struct SweepTicks {
    x_labels: Option<usize>,
    steps: (f64, f64),
    x_offset: Option<i128>,
}

/// A sweep figure's mesh: the axes' descriptions (`x_key`, `metric`) and tick labels, none
/// on an axis of one value (labelled by [`draw_single_value_labels`]).
fn draw_sweep_mesh<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    st: &Style,
    (x_key, metric): (&str, &str),
    axes: &SweepAxes,
    ticks: &SweepTicks,
) -> DrawResult {
    let (xs, ys) = ticks.steps;
    chart
        .configure_mesh()
        .x_desc(x_key)
        .y_desc(metric)
        // plotters' own default is 11 labels at most.
        .x_labels(ticks.x_labels.unwrap_or(11))
        .x_label_formatter(&|v| {
            if axes.single_x.is_some() {
                String::new()
            } else {
                x_tick_label(*v, xs, ticks.x_offset)
            }
        })
        .y_label_formatter(&|v| {
            if axes.single_y.is_some() {
                String::new()
            } else {
                tick_label(*v, ys)
            }
        })
        .label_style(st.font(0.95))
        .axis_desc_style(st.font(1.0))
        .draw()
        .map_err(s)
}

/// The one value of a sweep figure's axis of one value, labelled at the value by hand with a
/// tick (att38-7): below the x axis, left of the y axis.
fn draw_single_value_labels<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    chart: &MapChart<'_, DB>,
    st: &Style,
    axes: &SweepAxes,
) -> DrawResult {
    let f = st.base_font();
    let one_style = TextStyle::from(st.font(0.95));
    let tick = (0.5 * f) as i32;
    if let Some(v) = axes.single_x {
        let (px, py) = chart.backend_coord(&(v, axes.y.0));
        let text = single_value_label(v);
        root.draw(&PathElement::new(vec![(px, py), (px, py + tick)], BLACK))
            .map_err(s)?;
        root.draw_text(
            &text,
            &one_style.pos(plotters::style::text_anchor::Pos::new(
                plotters::style::text_anchor::HPos::Center,
                plotters::style::text_anchor::VPos::Top,
            )),
            (px, py + tick + (0.2 * f) as i32),
        )
        .map_err(s)?;
    }
    if let Some(v) = axes.single_y {
        let (px, py) = chart.backend_coord(&(axes.x.0, v));
        let text = single_value_label(v);
        root.draw(&PathElement::new(vec![(px - tick, py), (px, py)], BLACK))
            .map_err(s)?;
        root.draw_text(
            &text,
            &one_style.pos(plotters::style::text_anchor::Pos::new(
                plotters::style::text_anchor::HPos::Right,
                plotters::style::text_anchor::VPos::Center,
            )),
            (px - tick - (0.3 * f) as i32, py),
        )
        .map_err(s)?;
    }
    Ok(())
}

/// The width of a sweep axis round its one value `v` (att38-7): a fifth of `|v|`, or 1 for 0.
fn single_value_width(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        1.0
    } else {
        0.2 * v.abs()
    }
}

/// The label of a sweep axis's one value: as written in the results (the shortest decimal
/// that reads back), never a tick rounding of it; shortened to 10 significant digits when
/// longer (a metric's `9.999999999999998`).
fn single_value_label(v: f64) -> String {
    let exact = isotrack_core::numtext::Echo(v).to_string();
    if exact.chars().filter(char::is_ascii_digit).count() <= 10 {
        exact
    } else {
        let short = format!("{v:.9e}").parse::<f64>().unwrap_or(v);
        isotrack_core::numtext::Echo(short).to_string()
    }
}

/// The x labels of a sweep figure whose x values are all whole numbers (`team.count`, a
/// seed, a sample count), spanning at most 12: one at each whole number of `[xa, xb]`, so the
/// axis reads 3 and 4, not 3.0 to 3.9 without the 4 (plotters' own choice of at most 10
/// labels); `None` otherwise (the usual ticks).
fn whole_number_labels(xs: impl Iterator<Item = f64>, xa: f64, xb: f64) -> Option<usize> {
    let mut any = false;
    for x in xs.filter(|x| x.is_finite()) {
        if x.fract() != 0.0 {
            return None;
        }
        any = true;
    }
    let n = xb.floor() - xa.ceil() + 1.0;
    (any && (1.0..=12.0).contains(&n)).then_some(n as usize)
}

/// How many of `n` whole-number x labels, the widest `widest_px` wide, a plot `plot_w_px`
/// wide (base font `f` px) shows: all of them when they fit side by side with a gap of
/// 0.8 f after each, else as many as fit (at least 1; plotters then labels every 2nd, 5th,
/// ... whole number, as before c47423f).
fn whole_labels_that_fit(n: usize, widest_px: f64, plot_w_px: f64, f: f64) -> usize {
    let each = widest_px + 0.8 * f;
    if each.is_nan() || each <= 0.0 || n as f64 * each <= plot_w_px {
        return n;
    }
    ((plot_w_px / each).floor() as usize).clamp(1, n)
}

/// The most characters a sweep legend's label may have for its box ([`legend_box_px`]) to
/// be at most 0.9 of a plot `plot_w_px` wide (base font `f` px).
fn legend_chars_that_fit(plot_w_px: f64, f: f64) -> usize {
    let room = 0.9 * plot_w_px - 20.0 - 2.0 * f;
    (room / (0.6 * 0.95 * f)).max(0.0).floor() as usize
}

/// Group values as a legend shows them, each at most `max` characters: all as they are when
/// they fit; else a value too long as `…/` and its last path component (a file name), cut to
/// its last characters after `…` if still too long, when that keeps the values distinct;
/// else from where the values first differ (their common prefix left out, `…` for it, one `/`
/// before it kept), cut with a `…` at the end if still too long.
fn shortened_values(values: &[&str], max: usize) -> Vec<String> {
    let len = |v: &str| v.chars().count();
    if values.iter().all(|v| len(v) <= max) {
        return values.iter().map(|v| v.to_string()).collect();
    }
    let tail = |v: &str, keep: usize| -> String {
        let n = len(v);
        v.chars().skip(n.saturating_sub(keep)).collect()
    };
    let named: Vec<String> = values
        .iter()
        .map(|v| {
            if len(v) <= max {
                return v.to_string();
            }
            let name = match v.rfind(['/', '\\']) {
                Some(i) if i + 1 < v.len() => format!("\u{2026}{}", &v[i..]),
                _ => v.to_string(),
            };
            if len(&name) <= max {
                name
            } else {
                format!("\u{2026}{}", tail(v, max.saturating_sub(1)))
            }
        })
        .collect();
    let distinct = named.iter().collect::<std::collections::HashSet<_>>().len() == named.len();
    if distinct {
        return named;
    }
    // The characters all values share at their start (none for one value).
    let chars: Vec<Vec<char>> = values.iter().map(|v| v.chars().collect()).collect();
    let common = match chars.split_first() {
        Some((first, rest)) if !rest.is_empty() => (0..first.len())
            .take_while(|&i| rest.iter().all(|c| c.get(i) == Some(&first[i])))
            .count(),
        _ => 0,
    };
    chars
        .iter()
        .map(|c| {
            if c.len() <= max {
                return c.iter().collect();
            }
            let mut start = common.min(c.len().saturating_sub(1));
            if start > 0 && matches!(c[start - 1], '/' | '\\') {
                start -= 1;
            }
            let lead = if start > 0 { "\u{2026}" } else { "" };
            let room = max.saturating_sub(lead.chars().count());
            let shown: String = if c.len() - start <= room {
                c[start..].iter().collect()
            } else {
                let cut: String = c[start..start + room.saturating_sub(1)].iter().collect();
                format!("{cut}\u{2026}")
            };
            format!("{lead}{shown}")
        })
        .collect()
}

/// The sweep figure's plot area in pixels `(width, height)` on a `size` image with base font
/// `f` px: the image less the y labels' 5.6 f and the right margin's 2 f and 1 f, less the
/// title (about 2 f), the x labels' 3.2 f and the margins' 2 f (the layout of
/// [`sweep_figure`], to within a few pixels: enough to place its legend).
fn sweep_plot_px(size: (u32, u32), f: f64) -> (f64, f64) {
    let (w, h) = (f64::from(size.0), f64::from(size.1));
    ((w - 8.6 * f).max(1.0), (h - 7.2 * f).max(1.0))
}

/// A legend's box in pixels `(width, height)` for `rows` labels of at most `chars` characters
/// in plotters' series-label area at 0.95 f: a 20 px sample line and padding beside the
/// text (about 0.6 of the font size a character), a row a line of 1.25 x the font.
fn legend_box_px(chars: usize, rows: usize, f: f64) -> (f64, f64) {
    let font = 0.95 * f;
    (
        0.6 * font * chars as f64 + 20.0 + 2.0 * f,
        1.25 * font * rows as f64 + f,
    )
}

/// Where the sweep figure's legend goes and the top of its y axis: the first corner (upper
/// right, upper left, lower right, lower left) whose legend box covers none of the lines, their
/// dots and error bars, the axis unchanged; when every corner covers some, the upper right over
/// headroom added above the data (the y axis raised so the highest bar ends below the box).
fn sweep_legend_place(
    lines: &[SummaryLine],
    range: [f64; 4],
    plot_px: (f64, f64),
    legend_px: (f64, f64),
) -> (f64, SeriesLabelPosition) {
    let [xa, xb, ya, yb] = range;
    let fw = (legend_px.0 / plot_px.0).min(0.9);
    let fh = (legend_px.1 / plot_px.1).min(0.9);
    let (bw, bh) = (fw * (xb - xa), fh * (yb - ya));
    // [x0, x1, y0, y1] of the box in each corner, in the order tried.
    let corners = [
        (SeriesLabelPosition::UpperRight, [xb - bw, xb, yb - bh, yb]),
        (SeriesLabelPosition::UpperLeft, [xa, xa + bw, yb - bh, yb]),
        (SeriesLabelPosition::LowerRight, [xb - bw, xb, ya, ya + bh]),
        (SeriesLabelPosition::LowerLeft, [xa, xa + bw, ya, ya + bh]),
    ];
    for (at, b) in corners {
        if !lines.iter().any(|l| line_meets_box(&l.1, b)) {
            return (yb, at);
        }
    }
    let top = finite_bounds(lines.iter().flat_map(|l| l.1.iter().map(|p| p.1 + p.2))).1;
    // The top `fh` of the axis (and a 3 % gap) above `top`: top <= yb' - (fh + 0.03)(yb' - ya).
    let k = (fh + 0.03).min(0.9);
    let raised = (top - k * ya) / (1.0 - k);
    (
        if raised.is_finite() {
            raised.max(yb)
        } else {
            yb
        },
        SeriesLabelPosition::UpperRight,
    )
}

/// Whether one sweep line (its means joined, each with a bar of +-1 std) meets the box
/// `[x0, x1, y0, y1]`: a dot or bar inside it, or a point of a segment (16 along each).
fn line_meets_box(pts: &[(f64, f64, f64, usize)], b: [f64; 4]) -> bool {
    let inside = |x: f64, y: f64| x >= b[0] && x <= b[1] && y >= b[2] && y <= b[3];
    let bar = |p: &(f64, f64, f64, usize)| {
        p.0 >= b[0] && p.0 <= b[1] && p.1 + p.2 >= b[2] && p.1 - p.2 <= b[3]
    };
    pts.iter().any(bar)
        || pts.windows(2).any(|w| {
            (0..=16).any(|i| {
                let u = f64::from(i) / 16.0;
                inside(
                    w[0].0 + u * (w[1].0 - w[0].0),
                    w[0].1 + u * (w[1].1 - w[0].1),
                )
            })
        })
}

/// The sweep figure's default title: the metric against `x_key`, the runs drawn and those
/// without a value.
fn sweep_title(x_key: &str, metric: &str, runs: usize, skipped: usize) -> String {
    format!(
        "{metric} against {x_key}: mean \u{b1} 1 std over {runs} runs{}",
        if skipped > 0 {
            format!(" ({skipped} without a value)")
        } else {
            String::new()
        }
    )
}

/// The font size, relative to the base font `f` (px), of a `title` on a figure `w` px wide: a
/// long title gets a smaller font (down to 0.75) rather than running off the image, a short
/// one at most 1.4.
fn title_font_rel(title: &str, w: u32, f: f64) -> f64 {
    let chars = title.chars().count() as f64;
    (1.4 * (w as f64 / (0.62 * f)) / chars.max(1.0)).clamp(0.75, 1.4)
}

/// One group's line of the sweep figure in colour `c`, labelled `label` for the legend: the
/// means joined, an error bar of one standard deviation and a dot at each x.
fn draw_summary_line<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    pts: &[(f64, f64, f64, usize)],
    label: String,
    c: RGBColor,
    st: &Style,
) -> DrawResult {
    let (w2, r4, bar) = (st.px(2.0), st.px(4.0), st.px(8.0));
    chart
        .draw_series(LineSeries::new(
            pts.iter().map(|p| (p.0, p.1)),
            c.stroke_width(w2),
        ))
        .map_err(s)?
        .label(label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(w2)));
    chart
        .draw_series(pts.iter().map(|p| {
            let (lo, hi) = bar_ends(p);
            ErrorBar::new_vertical(p.0, lo, p.1, hi, c.filled(), bar)
        }))
        .map_err(s)?;
    chart
        .draw_series(pts.iter().map(|p| Circle::new((p.0, p.1), r4, c.filled())))
        .map_err(s)?;
    Ok(())
}

/// What [`team_figure`] draws: the gaps ahead along the isoline over time, the longest
/// unvisited time along it, their ideal values and the panels' (checked) ranges.
struct TeamFigureData {
    /// The vehicles.
    n: usize,
    /// The isoline's length, m.
    l: f64,
    /// `(t, gap ahead of each vehicle)`.
    gaps: Vec<(f64, Vec<f64>)>,
    /// `(position along the isoline, longest unvisited time)` over the steady window.
    revisit: Vec<(f64, f64)>,
    /// The revisit panel's label when it has no curve: why.
    no_revisit: String,
    /// `L/(N v0)` (`L/sum v0_i` with per-vehicle speeds), s (an open isoline: the mean gap
    /// over `v0`, `summary.json`'s).
    ideal: f64,
    /// `L/N`, m (an open isoline: the mean gap over the steady window, `summary.json`'s).
    even: f64,
    /// The ideal revisit time of the vehicles still flying (`summary.json`'s
    /// `revisit_time_ideal_active_s`) where a vehicle was lost and it differs from `ideal`
    /// (nu36-14), else NaN.
    ideal_active: f64,
    /// Whether the isoline is closed (else open: no gap ahead of the vehicle in front).
    closed: bool,
    /// Whether the field moves its isoline (the dashed lines of its mean length, the curves
    /// along its last frame).
    moving: bool,
    /// Whether the vehicles have their own nominal speeds (the ideal is then `L/sum v0_i`).
    per_vehicle_speeds: bool,
    t_end: f64,
    gap_range: (f64, f64),
    revisit_range: (f64, f64),
    /// The isoline the gaps and revisit times are measured along, as drawn (x, y), m.
    isoline: Vec<(f64, f64)>,
    /// Its legend label.
    isoline_label: String,
    /// Each vehicle's position at the last row (x, y), m.
    ends: Vec<(f64, f64)>,
    /// The isoline panel's range `[x0, x1, y0, y1]`, m.
    map_range: [f64; 4],
}

/// The runs of consecutive finite points of `points` (a NaN or infinite coordinate breaks the
/// line: an open isoline's vehicle in front has no gap ahead, a bin the team never covered no
/// revisit time).
fn finite_runs(points: impl Iterator<Item = (f64, f64)>) -> Vec<Vec<(f64, f64)>> {
    let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    for p in points {
        if p.0.is_finite() && p.1.is_finite() {
            if let Some(r) = runs.last_mut() {
                r.push(p);
            }
        } else if runs.last().is_some_and(|r| !r.is_empty()) {
            runs.push(Vec::new());
        }
    }
    runs.retain(|r| !r.is_empty());
    runs
}

/// The ideal levels [`team_figure`] draws dashed: the revisit time `ideal`, the gap `even`
/// and the ideal of the vehicles still flying `ideal_active` (NaN: none).
struct IdealLevels {
    ideal: f64,
    even: f64,
    ideal_active: f64,
}

impl IdealLevels {
    /// The levels of a team of `n` vehicles along an isoline of length `l` m, from the
    /// scenario of the team's first vehicle and the team's metrics in `summary.json`.
    fn of(
        first: &RunData,
        team: Option<&isotrack_runs::summary::TeamRecord>,
        (closed, moving): (bool, bool),
        l: f64,
        n: usize,
    ) -> Self {
        let v0 = first
            .scenario
            .spec()
            .team
            .as_ref()
            .map_or(first.scenario.spec().vehicle.speed_mps(), |t| {
                t.ideal_speed_mps()
            });
        // A field that moves its isoline: the figure measures along the last frame's, the
        // metrics along each sample's; the dashed lines are summary.json's, of the mean length
        // (nu-2: the last frame's drawn disagreed with summary.json without a word).
        let (ideal, even) = if closed && moving {
            (
                team.and_then(|m| m.revisit_time_ideal_s)
                    .unwrap_or(f64::NAN),
                team.and_then(|m| m.isoline_length_m)
                    .map_or(f64::NAN, |l| l / n as f64),
            )
        } else if closed {
            (l / (n as f64 * v0), l / n as f64)
        } else {
            // The metrics' own numbers for the stretch the team covered (NaN: none).
            (
                team.and_then(|m| m.revisit_time_ideal_s)
                    .unwrap_or(f64::NAN),
                team.and_then(|m| m.open_isoline.as_ref())
                    .and_then(|o| o.mean_gap_m)
                    .unwrap_or(f64::NAN),
            )
        };
        let ideal_active = team
            .and_then(|m| m.revisit_time_ideal_active_s)
            .filter(|a| a.is_finite() && ideal.is_finite() && *a != ideal)
            .unwrap_or(f64::NAN);
        Self {
            ideal,
            even,
            ideal_active,
        }
    }
}

/// Why the revisit panel of [`team_figure`] has no curve, as the run shows it: no metrics
/// sample in the steady window (`window` is `None`), or no vehicle live in it.
fn no_revisit_reason(first: &RunData, arc: &crate::team::FigureArc, window: Option<f64>) -> String {
    match window {
        None => format!(
            "no revisit time: no metrics sample in the steady window (sampled every {} s)",
            crate::style::value_label(
                first
                    .scenario
                    .team_metrics_every_steps(matches!(arc, crate::team::FigureArc::Circle(_)))
                    .max(1) as f64
                    * first.scenario.dt_s()
            )
        ),
        Some(_) => "no revisit time: no vehicle live in the steady window".to_string(),
    }
}

/// Each vehicle's last position (x, y), m, at its own end (NaN: no row).
fn last_positions(vehicles: &[RunData]) -> Vec<(f64, f64)> {
    vehicles
        .iter()
        .map(|v| {
            v.trace
                .last()
                .map_or((f64::NAN, f64::NAN), |r| (r.x_m, r.y_m))
        })
        .collect()
}

/// The isoline panel's square range `[x0, x1, y0, y1]`, m, round the isoline and the
/// vehicles' last positions (6 % of the side on each side); an error where it is not finite.
fn team_map_range(isoline: &[(f64, f64)], ends: &[(f64, f64)]) -> Result<[f64; 4], PlotError> {
    let (x0, x1) = finite_bounds(isoline.iter().chain(ends).map(|p| p.0));
    let (y0, y1) = finite_bounds(isoline.iter().chain(ends).map(|p| p.1));
    let side = (x1 - x0).max(y1 - y0).max(1e-6);
    let pad = 0.06 * side;
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let half = 0.5 * side + pad;
    let map_range = [cx - half, cx + half, cy - half, cy + half];
    padded_axis("x_m", map_range[0], map_range[1], 0.0, 0.0)?;
    padded_axis("y_m", map_range[2], map_range[3], 0.0, 0.0)?;
    Ok(map_range)
}

impl TeamFigureData {
    fn of(vehicles: &[RunData]) -> Result<Self, PlotError> {
        let tracks = crate::team::TeamTracks::new(vehicles).ok_or_else(|| {
            PlotError::Data(
                "the team's figure needs an isoline at controller.level to measure along, and the field has none there (docs/TEAMS.md)".into(),
            )
        })?;
        let first = &vehicles[0];
        let n = vehicles.len();
        let l = tracks.length_m();
        let stride = tracks.rows.div_ceil(2000).max(1);
        let gaps = tracks.gaps(stride);
        // The window the metrics took (their first sample in it; att32g-1, -2).
        let window = crate::team::metrics_window_start_s(&first.scenario, &tracks.arc);
        let mut revisit = tracks.revisit_max(window.unwrap_or(f64::INFINITY));
        // The figure agrees with summary.json: no revisit time where the metrics have none
        // (no vehicle live in the steady window; att32f-3).
        let team = first.summary.team().and_then(|t| t.metrics.as_ref());
        if team.is_some_and(|m| m.revisit_time_max_s.is_none()) {
            revisit.iter_mut().for_each(|r| r.1 = f64::NAN);
        }
        let no_revisit = no_revisit_reason(first, &tracks.arc, window);
        let closed = tracks.is_closed();
        let per_vehicle_speeds = first
            .scenario
            .spec()
            .team
            .as_ref()
            .is_some_and(|t| t.member_speeds().is_some());
        let moving = team.is_some_and(|m| m.moving_isoline.is_some());
        let IdealLevels {
            ideal,
            even,
            ideal_active,
        } = IdealLevels::of(first, team, (closed, moving), l, n);
        let isoline: Vec<(f64, f64)> = tracks.arc.points().iter().map(|p| (p.x, p.y)).collect();
        let ends = last_positions(vehicles);
        let map_range = team_map_range(&isoline, &ends)?;
        // To the last vehicle's end (att32f-3: the gaps' last time, which stops once fewer than
        // two vehicles are left, cut the axis short of the run).
        let t_end = tracks
            .end_s()
            .max(gaps.last().map_or(0.0, |g| g.0))
            .max(1e-9);
        padded_axis("t_s", 0.0, t_end, 0.0, 0.0)?;
        let (glo, ghi) = finite_bounds(gaps.iter().flat_map(|g| g.1.iter().copied()).chain([even]));
        let (glo, ghi) = padded_axis("gap_m", glo.min(0.0), ghi, 0.08, 1e-9)?.unwrap_or((0.0, 1.0));
        let (rlo, rhi) =
            finite_bounds(
                revisit
                    .iter()
                    .map(|r| r.1)
                    .chain([ideal, ideal_active, 0.0]),
            );
        let (rlo, rhi) = padded_axis("revisit_s", rlo, rhi, 0.08, 1e-9)?.unwrap_or((0.0, 1.0));
        Ok(Self {
            n,
            l,
            gaps,
            revisit,
            no_revisit,
            ideal,
            even,
            ideal_active,
            closed,
            moving,
            per_vehicle_speeds,
            t_end,
            gap_range: (glo, ghi),
            revisit_range: (rlo, rhi),
            isoline,
            isoline_label: tracks.isoline_label.clone(),
            ends,
            map_range,
        })
    }
}

/// A team's figure (issue 32, docs/TEAMS.md), from its trace: on top, the arc-length gap ahead
/// of each vehicle along the true isoline over time (one colour per vehicle, as in the
/// trajectory figure; the even gap `L/N` dashed); below, the longest time each point of the
/// isoline went without a visit over the steady window, along the isoline (the ideal
/// `L/(N v0)` dashed) and, beside it, the isoline they are measured along as drawn (the
/// metrics' own: a radial field's circle, a static field's marching-squares polyline, closed or
/// open, or for a field that moves the isoline at the last row, labelled so;
/// [`crate::team::figure_isoline`]) with each vehicle's last position. On an open isoline the
/// gaps are between consecutive vehicles only (the one in front has none), the revisit times
/// over the stretch the team covered, and the dashed lines the mean gap and its revisit time
/// from `summary.json`. `vehicles` as [`RunData::load_team`] gives them. A data error when the
/// field has no isoline at the level.
pub fn team_figure(
    vehicles: &[RunData],
    path: &Path,
    st: &Style,
    title: &str,
) -> Result<(), PlotError> {
    let title = st.title(title);
    let data = TeamFigureData::of(vehicles)?;
    let (w, h) = st.size((1100, 760), (560, 420));
    render!(path, st.format, (w, h), |root| {
        (|| -> DrawResult {
            root.fill(&WHITE).map_err(s)?;
            let body = if title.is_empty() {
                root.clone()
            } else {
                root.titled(title, st.font(1.6)).map_err(s)?
            };
            let areas = body.split_evenly((2, 1));
            let (bw, _) = areas[1].dim_in_pixel();
            let (revisit_area, map_area) = areas[1].split_horizontally((bw as f64 * 0.62) as u32);
            draw_team_gaps(&areas[0], st, &data, vehicles)?;
            draw_team_revisit(&revisit_area, st, &data)?;
            draw_team_isoline(&map_area, st, &data)
        })()
    })
}

/// A dashed black level line from `a` to `b`, as [`team_figure`]'s panels draw their ideal
/// and even-gap levels.
fn dashed_level(
    st: &Style,
    a: (f64, f64),
    b: (f64, f64),
) -> DashedLineSeries<std::array::IntoIter<(f64, f64), 2>, u32> {
    DashedLineSeries::new(
        [a, b],
        st.px(8.0),
        st.px(5.0),
        BLACK.stroke_width(st.px(2.0)),
    )
}

/// [`team_figure`]'s top panel: the gap ahead of each vehicle over time, the even gap dashed.
fn draw_team_gaps<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    st: &Style,
    d: &TeamFigureData,
    vehicles: &[RunData],
) -> DrawResult {
    let (glo, ghi) = d.gap_range;
    let (ts, gs) = (tick_step(0.0, d.t_end, 10), tick_step(glo, ghi, 8));
    let (w2, w3) = (st.px(2.0), st.px(3.0));
    let mut top = panel_axes(
        area,
        st,
        ((0.0, d.t_end), (glo, ghi)),
        ("time (s)", "gap ahead along the isoline (m)"),
        (ts, gs),
    )?;
    if d.even.is_finite() {
        top.draw_series(dashed_level(st, (0.0, d.even), (d.t_end, d.even)))
            .map_err(s)?
            .label(match (d.closed, d.moving) {
                (true, false) => "even gap L/N",
                (true, true) => "even gap L/N, L the mean length",
                (false, _) => "mean gap S/(N-1)",
            })
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(w2))
            });
    }
    for (i, v) in vehicles.iter().enumerate() {
        let c = colour(i);
        let series = top
            .draw_series(
                finite_runs(d.gaps.iter().map(|g| (g.0, g.1[i])))
                    .into_iter()
                    .map(|r| PathElement::new(r, c.stroke_width(w2))),
            )
            .map_err(s)?;
        if d.n <= RUN_COLOURS.len() {
            series.label(v.name.clone()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(w3))
            });
        }
    }
    // nu36-2: the even gap drawn again over the vehicles' gaps, which settle on it and
    // hid it (its legend entry stays first).
    if d.even.is_finite() {
        top.draw_series(dashed_level(st, (0.0, d.even), (d.t_end, d.even)))
            .map_err(s)?;
    }
    panel_legend(&mut top, st, SeriesLabelPosition::UpperRight)
}

/// [`team_figure`]'s lower left panel: the longest unvisited time along the isoline, the
/// ideal dashed (and that of the vehicles still flying dotted), the key in a free corner.
fn draw_team_revisit<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    st: &Style,
    d: &TeamFigureData,
) -> DrawResult {
    let (l, (rlo, rhi)) = (d.l, d.revisit_range);
    let (ls, rs) = (tick_step(0.0, l, 10), tick_step(rlo, rhi, 8));
    let (w2, w3) = (st.px(2.0), st.px(3.0));
    let mut bottom = panel_axes(
        area,
        st,
        ((0.0, l), (rlo, rhi)),
        (
            "position along the isoline, in the direction of travel (m)",
            "longest unvisited time (s)",
        ),
        (ls, rs),
    )?;
    draw_ideal_lines(&mut bottom, st, d)?;
    let c = colour(1);
    let revisits = finite_runs(d.revisit.iter().copied());
    let label = if revisits.is_empty() {
        d.no_revisit.as_str()
    } else if d.moving {
        "revisit time, steady window, along the last frame"
    } else {
        "revisit time, steady window"
    };
    bottom
        .draw_series(
            revisits
                .into_iter()
                .map(|r| PathElement::new(r, c.stroke_width(w2))),
        )
        .map_err(s)?
        .label(label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(w3)));
    // nu36-2: the ideal drawn again over the revisit curve, which lies on it for an even
    // team and hid it (its legend entry stays first).
    if d.ideal.is_finite() {
        bottom
            .draw_series(dashed_level(st, (0.0, d.ideal), (l, d.ideal)))
            .map_err(s)?;
    }
    // att36-14: the key in the corner the curve and the ideal line leave free (it sat
    // at the lower right over a low revisit curve and hid it).
    let mut drawn: Vec<(f64, f64)> = d
        .revisit
        .iter()
        .copied()
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    for level in [d.ideal, d.ideal_active] {
        if level.is_finite() {
            drawn.extend((0..=64).map(|k| (l * f64::from(k) / 64.0, level)));
        }
    }
    let corner = quiet_corner(&drawn, (0.0, l), (rlo, rhi));
    panel_legend(&mut bottom, st, corner)
}

/// The ideal revisit time dashed across [`team_figure`]'s revisit panel, and where a vehicle
/// was lost that of the vehicles still flying dotted, each with its legend entry.
fn draw_ideal_lines<DB: DrawingBackend>(
    bottom: &mut MapChart<'_, DB>,
    st: &Style,
    d: &TeamFigureData,
) -> DrawResult {
    let l = d.l;
    let w2 = st.px(2.0);
    if d.ideal.is_finite() {
        // Dashed in the legend as on the panel (att32d-16: drawn solid there), and
        // with per-vehicle speeds its own formula, `L/sum v0_i`.
        let (dash, gap) = (st.px(6.0), st.px(3.0));
        bottom
            .draw_series(dashed_level(st, (0.0, d.ideal), (l, d.ideal)))
            .map_err(s)?
            .label(match (d.closed, d.per_vehicle_speeds, d.moving) {
                (true, false, false) => "ideal L/(N v0)",
                (true, true, false) => "ideal L/sum v0_i",
                (true, false, true) => "ideal L/(N v0), L the mean length",
                (true, true, true) => "ideal L/sum v0_i, L the mean length",
                (false, _, _) => "ideal S/((N-1) v0)",
            })
            .legend(move |(x, y)| {
                plotters::element::DashedPathElement::new(
                    vec![(x, y), (x + 20, y)],
                    dash,
                    gap,
                    BLACK.stroke_width(w2),
                )
            });
    }
    // nu36-14: a team that lost a vehicle: the ideal of those still flying too, dotted
    // (the revisit curve settles on it, not on the deployed ideal).
    if d.ideal_active.is_finite() {
        let (dot, gap) = (st.px(2.0), st.px(4.0));
        bottom
            .draw_series(std::iter::once(plotters::element::DashedPathElement::new(
                vec![(0.0, d.ideal_active), (l, d.ideal_active)],
                dot,
                gap,
                BLACK.stroke_width(w2),
            )))
            .map_err(s)?
            .label("ideal of the vehicles still flying")
            .legend(move |(x, y)| {
                plotters::element::DashedPathElement::new(
                    vec![(x, y), (x + 20, y)],
                    dot,
                    gap,
                    BLACK.stroke_width(w2),
                )
            });
    }
    Ok(())
}

/// [`team_figure`]'s lower right panel: the isoline the panels measure along, and where each
/// vehicle ended; its key above the panel, outside the axes (nu-1: the key's box was cut at
/// the figure's edge; nu-7: it covered a vehicle's last position).
fn draw_team_isoline<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    st: &Style,
    d: &TeamFigureData,
) -> DrawResult {
    let (w2, w3) = (st.px(2.0), st.px(3.0));
    let f = st.base_font();
    let (key_area, map_area) = area.split_vertically((2.0 * f) as u32);
    draw_line_key(&key_area, st, &d.isoline_label, (5.6 + 0.75) * f, w3)?;
    let [mx0, mx1, my0, my1] = d.map_range;
    let ms = tick_step(mx0, mx1, 5);
    let (mw, _) = map_area.dim_in_pixel();
    let label_style = TextStyle::from(st.font(0.95));
    let x_labels = x_labels_that_fit(st, mw, (mx0, mx1), ms, |t| {
        map_area
            .estimate_text_size(t, &label_style)
            .map_or(0.6 * 0.95 * f * t.chars().count() as f64, |(w, _)| w as f64)
    });
    let mut map = panel_axes_labelled(
        &map_area,
        st,
        ((mx0, mx1), (my0, my1)),
        ("x (m)", "y (m)"),
        (ms, ms),
        x_labels,
    )?;
    map.draw_series(
        finite_runs(d.isoline.iter().copied())
            .into_iter()
            .map(|r| PathElement::new(r, BLACK.stroke_width(w2))),
    )
    .map_err(s)?;
    for (i, e) in d.ends.iter().enumerate() {
        if e.0.is_finite() && e.1.is_finite() {
            map.draw_series([Circle::new(*e, st.px(6.0), colour(i).filled())])
                .map_err(s)?;
        }
    }
    Ok(())
}

/// A key of one black line labelled `label` in `area` (a strip above a panel), from `x0_px`:
/// the text at the panel's label size, smaller where it would not fit the strip's width (down
/// to half of it).
fn draw_line_key<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    st: &Style,
    label: &str,
    x0_px: f64,
    stroke_px: u32,
) -> DrawResult {
    let f = st.base_font();
    let (w, h) = area.dim_in_pixel();
    let y = (0.5 * h as f64) as i32;
    let x0 = x0_px as i32;
    let line = st.px(20.0) as i32;
    let text_x = x0 + line + (0.5 * f) as i32;
    let room = (w as f64 - text_x as f64 - 0.5 * f).max(1.0);
    let mut rel = 0.95;
    if let Ok((tw, _)) = area.estimate_text_size(label, &TextStyle::from(st.font(rel))) {
        if tw as f64 > room {
            rel = (rel * room / tw as f64).max(0.5 * rel);
        }
    }
    area.draw(&PathElement::new(
        vec![(x0, y), (x0 + line, y)],
        BLACK.stroke_width(stroke_px),
    ))
    .map_err(s)?;
    area.draw(&Text::new(
        label.to_string(),
        (text_x, y),
        TextStyle::from(st.font(rel)).pos(plotters::style::text_anchor::Pos::new(
            plotters::style::text_anchor::HPos::Left,
            plotters::style::text_anchor::VPos::Center,
        )),
    ))
    .map_err(s)
}

/// One panel's axes, as [`timeseries_figure`]'s and [`team_figure`]'s panels share them: over
/// `x` and `y`, with their descriptions and tick labels (at the steps given), no grid lines.
fn panel_axes<'a, DB: DrawingBackend + 'a>(
    area: &'a DrawingArea<DB, Shift>,
    st: &Style,
    ranges: ((f64, f64), (f64, f64)),
    descs: (&str, &str),
    ticks: (f64, f64),
) -> Result<MapChart<'a, DB>, String> {
    panel_axes_labelled(area, st, ranges, descs, ticks, None)
}

/// [`panel_axes`] with at most `x_labels` labels on the x axis (`None`: plotters' default).
fn panel_axes_labelled<'a, DB: DrawingBackend + 'a>(
    area: &'a DrawingArea<DB, Shift>,
    st: &Style,
    (x, y): ((f64, f64), (f64, f64)),
    (x_desc, y_desc): (&str, &str),
    (x_tick, y_tick): (f64, f64),
    x_labels: Option<usize>,
) -> Result<MapChart<'a, DB>, String> {
    let f = st.base_font();
    let mut chart = ChartBuilder::on(area)
        .margin((0.75 * f) as u32)
        .margin_right((2.0 * f) as u32)
        .x_label_area_size((2.8 * f) as u32)
        .y_label_area_size((5.6 * f) as u32)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)
        .map_err(s)?;
    let x_fmt = |v: &f64| tick_label(*v, x_tick);
    let y_fmt = |v: &f64| tick_label(*v, y_tick);
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_desc)
        .y_desc(y_desc)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style(st.font(0.95))
        .axis_desc_style(st.font(1.0))
        .light_line_style(WHITE.mix(0.0));
    if let Some(n) = x_labels {
        mesh.x_labels(n);
    }
    mesh.draw().map_err(s)?;
    Ok(chart)
}

/// How many x labels fit side by side on a panel of `area_w_px` ([`panel_axes`]' margins and
/// y label area off it) over `[x0, x1]` labelled at `step`, a label `width_px` wide (as drawn)
/// and `0.8 em` from the next: `None` when the usual ones do, else fewer (nu-8: a
/// kilometre-scale field ran its six-digit labels together).
fn x_labels_that_fit(
    st: &Style,
    area_w_px: u32,
    (x0, x1): (f64, f64),
    step: f64,
    width_px: impl Fn(&str) -> f64,
) -> Option<usize> {
    let f = st.base_font();
    let plot_w = area_w_px as f64 - (0.75 + 2.0 + 5.6) * f;
    // The labels plotters draws at its default count of 11 (its steps are 1, 2, 5 times a
    // power of ten, as `tick_step`'s), each with a gap after it.
    let usual = tick_step(x0, x1, 11);
    if !(usual > 0.0 && usual.is_finite()) {
        return None;
    }
    let first = (x0 / usual).ceil() as i64;
    let last = (x1 / usual).floor() as i64;
    let gap = 0.8 * f;
    let (mut total, mut widest, mut count) = (0.0, 0.0f64, 0usize);
    for k in first..=last.min(first.saturating_add(100)) {
        let w = width_px(&tick_label(k as f64 * usual, step));
        total += w + gap;
        widest = widest.max(w);
        count += 1;
    }
    if count == 0 || total <= plot_w {
        None
    } else {
        let label_w = widest + gap;
        Some(((plot_w / label_w).floor() as usize).max(2))
    }
}

/// A panel's legend ([`panel_axes`]), at `at`.
/// The corner of a panel over `x` x `y` for a legend box that covers the fewest of `points`
/// (the box taken as 55 % of the width and 30 % of the height from the corner), in the order
/// lower right, upper right, upper left, lower left on a tie (att36-14).
fn quiet_corner(points: &[(f64, f64)], x: (f64, f64), y: (f64, f64)) -> SeriesLabelPosition {
    let (w, h) = (x.1 - x.0, y.1 - y.0);
    let count = |right: bool, upper: bool| {
        points
            .iter()
            .filter(|p| {
                let fx = (p.0 - x.0) / w;
                let fy = (p.1 - y.0) / h;
                let in_x = if right { fx >= 0.45 } else { fx <= 0.55 };
                let in_y = if upper { fy >= 0.7 } else { fy <= 0.3 };
                in_x && in_y
            })
            .count()
    };
    [
        (SeriesLabelPosition::LowerRight, true, false),
        (SeriesLabelPosition::UpperRight, true, true),
        (SeriesLabelPosition::UpperLeft, false, true),
        (SeriesLabelPosition::LowerLeft, false, false),
    ]
    .into_iter()
    .min_by_key(|&(_, r, u)| count(r, u))
    .map_or(SeriesLabelPosition::LowerRight, |c| c.0)
}

fn panel_legend<'a, DB: DrawingBackend + 'a>(
    chart: &mut MapChart<'a, DB>,
    st: &Style,
    at: SeriesLabelPosition,
) -> DrawResult {
    chart
        .configure_series_labels()
        .label_font(st.font(0.95))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(at)
        .draw()
        .map_err(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// att46-17: beyond [`FULL_MARK_PATHS`] paths the marks lose their white ring and arrow,
    /// and all of them together cover at most the area of [`FULL_MARK_PATHS`] full ones
    /// (`n pi r^2 <= 16 pi 7^2` px^2, to the rounding of `r` to whole pixels: `r <= 7
    /// sqrt(16/n) + 0.5`); a mark under a pixel is left out (5000 paths in SVG: `7 sqrt(16 /
    /// 5000) = 0.40 px`). Up to 16 the full marks (a team of 4 is drawn as before).
    #[test]
    fn many_paths_get_small_marks_without_rings() {
        let st = Style::new(Format::Svg);
        for n in [1, 4, 16] {
            let m = PathMarks::of(n, &st);
            assert_eq!(
                (m.start_px, m.end_px, m.ring, m.arrow),
                (Some(7), Some(9), true, true)
            );
        }
        for n in [17, 100, 300, 784] {
            let m = PathMarks::of(n, &st);
            assert!(!m.ring && !m.arrow, "{n}: {m:?}");
            let r = m.start_px.unwrap() as f64;
            assert!(r <= 7.0 * (16.0 / n as f64).sqrt() + 0.5, "{n}: {r}");
            let e = m.end_px.unwrap() as f64;
            assert!(e <= 9.0 * (16.0 / n as f64).sqrt() + 0.5, "{n}: {e}");
        }
        let m = PathMarks::of(5000, &st);
        assert_eq!((m.start_px, m.end_px), (None, None));
    }

    /// att36-14: the revisit panel's key goes where neither the curve nor the ideal line is:
    /// a low curve (ERA5 at 600 s: 300-600 s under an ideal near the top) leaves the upper
    /// corners to the ideal and the lower ones to the curve, the key taking the one with the
    /// fewest points; a curve on the ideal in the middle leaves the lower right free.
    #[test]
    fn the_revisit_key_takes_a_free_corner() {
        let l = 580.0;
        let curve: Vec<(f64, f64)> = (0..=100).map(|k| (l * k as f64 / 100.0, 400.0)).collect();
        let at = |pts: &[(f64, f64)]| quiet_corner(pts, (0.0, l), (0.0, 5000.0));
        // The curve low everywhere: an upper corner.
        assert!(matches!(at(&curve), SeriesLabelPosition::UpperRight));
        // The curve low on the right only, high on the left: lower left is busy, lower right
        // too; upper right is free.
        let mixed: Vec<(f64, f64)> = curve
            .iter()
            .map(|&(x, y)| (x, if x < 0.5 * l { 4500.0 } else { y }))
            .collect();
        assert!(matches!(at(&mixed), SeriesLabelPosition::UpperRight));
        // In the middle: lower right, as before.
        let mid: Vec<(f64, f64)> = curve.iter().map(|&(x, _)| (x, 2500.0)).collect();
        assert!(matches!(at(&mid), SeriesLabelPosition::LowerRight));
    }

    /// att38-7: one sweep value's axis is a fifth of it wide round it (1 round 0) and its
    /// label is the value as written.
    #[test]
    fn one_value_axes() {
        assert!((single_value_width(5.5) - 1.1).abs() < 1e-15);
        assert_eq!(single_value_width(0.0), 1.0);
        assert_eq!(single_value_label(5.5), "5.5");
        assert_eq!(single_value_label(0.1), "0.1");
        assert_eq!(single_value_label(-1234567.5), "-1234567.5");
        assert_eq!(single_value_label(9.999999999999998), "10");
    }

    /// nu-7: a sweep over `team.count = [3, 4]` is labelled at 3 and 4 (the axis padded by 5 %
    /// each side, 2.95 to 4.05, holds the two whole numbers); half values, or whole numbers
    /// spanning more than 12, keep the usual ticks.
    #[test]
    fn whole_number_x_values_get_a_label_at_each() {
        assert_eq!(
            whole_number_labels([3.0, 4.0, 3.0].into_iter(), 2.95, 4.05),
            Some(2)
        );
        assert_eq!(
            whole_number_labels([1.0, 8.0].into_iter(), 0.65, 8.35),
            Some(8)
        );
        assert_eq!(whole_number_labels([3.0, 3.5].into_iter(), 2.9, 3.6), None);
        assert_eq!(
            whole_number_labels([0.0, 20.0].into_iter(), -1.0, 21.0),
            None
        );
        assert_eq!(whole_number_labels(std::iter::empty(), 0.0, 4.0), None);
        // att30n-7: one whole value on its axis one unit wide (padded 5 %): one label.
        assert_eq!(whole_number_labels([5.0].into_iter(), 4.45, 5.55), Some(1));
    }

    /// att30n-15: twelve labels 117 px wide with a gap of 0.8 x 16 px need 12 x 129.8 =
    /// 1558 px: on a plot 862 px wide 6 fit (862 / 129.8 = 6.6); eight 10 px labels, 8 x
    /// 22.8 = 182 px, all fit; one label wider than the plot is still drawn.
    #[test]
    fn whole_number_labels_are_as_many_as_fit() {
        assert_eq!(whole_labels_that_fit(12, 117.0, 862.0, 16.0), 6);
        assert_eq!(whole_labels_that_fit(8, 10.0, 862.0, 16.0), 8);
        assert_eq!(whole_labels_that_fit(3, 2000.0, 862.0, 16.0), 1);
    }

    /// att30n-8: a legend's labels at most as wide as 0.9 of the plot: on a plot 862 px
    /// wide at 16 px, (0.9 x 862 - 20 - 32) / (0.6 x 0.95 x 16) = 723.8 / 9.12 = 79
    /// characters. Values too long show a path's file name after an ellipsis when that keeps
    /// them apart, else their ends round one; short values stay as they are.
    #[test]
    fn long_legend_values_are_shortened_to_fit() {
        assert_eq!(legend_chars_that_fit(862.0, 16.0), 79);
        let dir = format!("/tmp/longdir/{}", "a".repeat(60));
        let (a, b) = (format!("{dir}/first.csv"), format!("{dir}/second.csv"));
        assert_eq!(
            shortened_values(&[&a, &b], 40),
            ["\u{2026}/first.csv", "\u{2026}/second.csv"]
        );
        assert_eq!(shortened_values(&["short", "also"], 40), ["short", "also"]);
        // One file name in two folders: shown from where they differ (none in common here).
        let (c, d) = (
            format!("/x/{}/map.csv", "b".repeat(50)),
            format!("/y/{}/map.csv", "b".repeat(50)),
        );
        let got = shortened_values(&[&c, &d], 40);
        assert_eq!(got[0], format!("/x/{}\u{2026}", "b".repeat(36)));
        assert_ne!(got[0], got[1]);
        assert!(got.iter().all(|v| v.chars().count() == 40), "{got:?}");
        // Two long file names sharing their ends, in one long folder (att30n-8's): from the
        // folder's last `/` on, cut at the end.
        let (f, s) = (
            format!("{dir}/first_variant_of_the_map_with_a_long_name.csv"),
            format!("{dir}/second_variant_of_the_map_with_a_long_name.csv"),
        );
        let got = shortened_values(&[&f, &s], 36);
        assert_eq!(
            got,
            [
                "\u{2026}/first_variant_of_the_map_with_a_l\u{2026}",
                "\u{2026}/second_variant_of_the_map_with_a_\u{2026}"
            ]
        );
        // A file name longer than the room: its last characters.
        let e = format!("/d/{}.csv", "c".repeat(60));
        let got = shortened_values(&[&e], 20);
        assert_eq!(got, [format!("\u{2026}{}.csv", "c".repeat(15))]);
    }

    /// nu-7: a flat line at 1.40 along the top of the axis and one at 0 along its bottom
    /// leave no corner free for a legend 30 % wide and 12 % tall: the axis is raised until
    /// the highest point (1.40) lies below the box in the upper right, by the box's own rule.
    /// Lines in the lower half only leave the upper right free, the axis unchanged; the sweep
    /// of `team.spacing` over `team.count` (none: 1.21 at 3, 1.40 at 4, under the box in the
    /// upper right only) the upper left.
    #[test]
    fn the_sweep_legend_covers_no_data() {
        let line = |name: &str, y3: f64, y4: f64| -> SummaryLine {
            (name.into(), vec![(3.0, y3, 0.0, 1), (4.0, y4, 0.0, 1)])
        };
        let (ya, yb) = (-0.112, 1.512);
        let plot = (1000.0, 500.0);
        let legend = (300.0, 60.0);
        let both = [line("top", 1.40, 1.40), line("rb", 0.0, 0.0)];
        let (top, at) = sweep_legend_place(&both, [2.95, 4.05, ya, yb], plot, legend);
        assert_eq!(at, SeriesLabelPosition::UpperRight);
        let box_bottom = top - 60.0 / 500.0 * (top - ya);
        assert!(
            top > yb && 1.40 < box_bottom,
            "top {top}, box from {box_bottom}"
        );
        let low: SummaryLine = ("low".into(), vec![(3.0, 0.1, 0.05, 1), (4.0, 0.3, 0.05, 1)]);
        let (top, at) = sweep_legend_place(&[low], [2.95, 4.05, 0.0, 1.0], plot, legend);
        assert_eq!((top, at), (1.0, SeriesLabelPosition::UpperRight));
        let sweep = [line("none", 1.21, 1.40), line("rb", 0.0, 0.0)];
        let (top, at) = sweep_legend_place(&sweep, [2.95, 4.05, ya, yb], plot, legend);
        assert_eq!((top, at), (yb, SeriesLabelPosition::UpperLeft));
    }

    /// Issue 30: on cells twice as wide as tall (dx = 2 m, dy = 1 m) the isoline of the cone
    /// `F = |p|` at level 40 m is the whole circle of radius 40 m: every end point within the
    /// grid's error of the radius (linear interpolation's on a 2 m edge with the field itself,
    /// half a cell's diagonal with the raster's nearest samples) and the length that of the circle
    /// (a polygon of 2 m chords: within 1 % of 2 pi 40 m). With one step min(dx, dy) along both
    /// axes the lattice covered x up to 0 only: half the circle.
    #[test]
    fn isoline_on_non_square_cells_is_the_whole_circle() {
        let (dx, dy, nx, ny) = (2.0, 1.0, 100, 100);
        let (x0, y0) = (-0.5 * dx * nx as f64, -0.5 * dy * ny as f64);
        let radius_m = 40.0;
        let cone = |p: Vec2| Some(p.norm());
        let values = (0..ny)
            .flat_map(|j| {
                (0..nx).map(move |i| {
                    cone(Vec2::new(
                        x0 + (i as f64 + 0.5) * dx,
                        y0 + (j as f64 + 0.5) * dy,
                    ))
                })
            })
            .collect();
        let raster = Raster {
            x0,
            y0,
            dx,
            dy,
            nx,
            ny,
            values,
        };
        let half_diagonal_m = 0.5 * (dx * dx + dy * dy).sqrt();
        // Linear interpolation along an edge of length h misses F by at most h^2 / 8 times
        // F'' <= 1 / r (r >= R - dx near the level set), and |grad F| = 1.
        let sag_m = dx * dx / (8.0 * (radius_m - dx));
        for (iso, tol_m) in [
            (raster.isoline(radius_m, cone), sag_m + 1e-9),
            (raster.isoline(radius_m, |p| raster.at(p)), half_diagonal_m),
        ] {
            let segs = iso.segments();
            assert!(!segs.is_empty());
            let mut length_m = 0.0;
            let (mut xmax, mut xmin, mut ymax, mut ymin) = (-1e9_f64, 1e9_f64, -1e9_f64, 1e9_f64);
            for (a, b) in segs {
                for p in [a, b] {
                    assert!(
                        (p.norm() - radius_m).abs() <= tol_m,
                        "{p:?} at {} m",
                        p.norm()
                    );
                    (xmax, xmin) = (xmax.max(p.x), xmin.min(p.x));
                    (ymax, ymin) = (ymax.max(p.y), ymin.min(p.y));
                }
                length_m += (*b - *a).norm();
            }
            let circle_m = 2.0 * std::f64::consts::PI * radius_m;
            assert!(
                (length_m - circle_m).abs() < 0.01 * circle_m,
                "{length_m} m of {circle_m} m"
            );
            for extreme in [xmax, -xmin, ymax, -ymin] {
                assert!((extreme - radius_m).abs() <= tol_m + dx, "{extreme}");
            }
        }
    }

    /// nu-20: `plot SWEEP --x team.spacing` (a text key) or `--metric order_preserved` (a
    /// boolean) over rows that all have both said "no run has both": the message says --x must
    /// be numeric (a text key goes to --group), which value was not a number, and which columns
    /// hold numbers. An empty column keeps the old message.
    #[test]
    fn a_text_key_or_a_boolean_metric_is_named_as_not_a_number() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("results.csv");
        std::fs::write(
            &p,
            "run_id,team.spacing,team.k_v,gap_cv,order_preserved,empty\n0,none,0.05,0.1,true,\n1,range_balance,0.1,0.02,true,\n",
        )
        .unwrap();
        let e = |x: &str, m: &str| match sweep_summary(&p, x, m, None) {
            Err(PlotError::Data(m)) => m,
            other => panic!("{other:?}"),
        };
        let m = e("team.spacing", "gap_cv");
        assert!(m.contains("`team.spacing` is text (e.g. `none`): --x must be a numeric key (a text key such as team.spacing or controller.kind goes to --group)"), "{m}");
        assert!(
            m.contains("the columns holding numbers: run_id, team.k_v, gap_cv"),
            "{m}"
        );
        assert!(!m.contains("gap_cv` is not"), "{m}");
        let m = e("team.k_v", "order_preserved");
        assert!(m.contains("`order_preserved` is not a number (e.g. `true`): --metric must be a numeric column"), "{m}");
        assert!(
            m.contains("the columns holding numbers: run_id, team.k_v, gap_cv"),
            "{m}"
        );
        assert!(!m.contains("--x must"), "{m}");
        let m = e("team.k_v", "empty");
        assert!(m.ends_with("no run has both `team.k_v` and `empty`"), "{m}");
        // Numeric x and metric: the summary as before.
        let (lines, skipped) = sweep_summary(&p, "team.k_v", "gap_cv", None).unwrap();
        assert_eq!(skipped, 0);
        assert_eq!(lines[0].1.len(), 2);
    }
}
