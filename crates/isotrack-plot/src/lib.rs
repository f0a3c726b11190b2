//! # isotrack-plot
//!
//! Publication figures from isotrack's own outputs, never by re-simulating:
//!
//! * [`RunData::load`] reads a run directory (`trace.csv`, `summary.json`, the resolved
//!   `scenario.toml`, whose field is rebuilt to draw the map);
//! * [`trajectory_figure`]: the trajectories over the field (heat map with a colour bar and
//!   units, the target isoline bold and a few others thin, start marker with a heading arrow,
//!   end marker, equal axis scales, axes in metres, legend when several runs are overlaid);
//! * [`timeseries_figure`]: error, measurement and turn rate against time, the steady-state
//!   window shaded;
//! * [`team_figure`]: a team's gaps over time and revisit time along the isoline
//!   ([`RunData::load_team`] reads a team's run as its vehicles);
//! * [`field_map`]: a field alone (the paper's Fig. 1(a));
//! * [`FieldPicture`]: a field sampled on a grid round some paths, with its isoline (the data
//!   the HTML pages draw);
//! * [`stability_map_figure`]: `isotrack check --map`'s chart of the sampled loop's spectral
//!   radius over `kp` x sensor rate.
//!
//! PNG or SVG; the font (DejaVu Sans, `assets/`) is compiled in, so no system font is needed.
#![deny(missing_docs)]

mod bitmap;
mod draw;
mod error;
mod limits;
mod mark;
mod picture;
mod run_data;
mod stability;
mod style;
mod team;

pub use draw::{
    animation_gif, animation_gif_team, field_map, sweep_figure, sweep_summary, team_figure,
    timeseries_figure, trajectory_figure, Panels, SummaryLine,
};
pub(crate) use error::open_input;
pub use error::{PlotError, MAX_INPUT_BYTES};
pub use mark::{figure_status, is_isotrack_figure, refuse_foreign_figure, FigureStatus};
pub use picture::FieldPicture;
pub use run_data::{data_files_unchanged, same_field, unrecorded_data_files_note, RunData};
pub use stability::{boundary_segments, stability_map_figure};
pub(crate) use style::fonts;
pub use style::{tick_label, tick_step, Colormap, Format, Style, DEFAULT_FONT_FAMILY};
pub use team::{figure_isoline, metrics_window_start_s, FigureArc, TeamTracks, REVISIT_BINS};
