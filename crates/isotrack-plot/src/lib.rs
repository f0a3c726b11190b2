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
//! * [`field_map`]: a field alone (the paper's Fig. 1(a));
//! * [`stability_map_figure`]: `isotrack check --map`'s chart of the sampled loop's spectral
//!   radius over `kp` x sensor rate.
//!
//! PNG or SVG; the font (DejaVu Sans, `assets/`) is compiled in, so no system font is needed.
#![deny(missing_docs)]

mod draw;
mod run_data;
mod stability;
mod style;

pub use draw::{
    animation_gif, field_map, sweep_figure, sweep_summary, timeseries_figure, trajectory_figure,
    Format, Panels, SummaryLine,
};
pub use run_data::{same_field, RunData};
pub use stability::{boundary_segments, stability_map_figure};
pub use style::{tick_label, tick_step, Colormap, Style, DEFAULT_FONT_FAMILY};

/// Why a figure could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// A run directory or one of its files is missing or cannot be read.
    #[error("{0}")]
    Input(String),
    /// A file was read but its content cannot be plotted (malformed, or values no axis can
    /// show).
    #[error("{0}")]
    Data(String),
    /// Drawing or writing the image failed.
    #[error("cannot draw {path}: {message}")]
    Draw {
        /// The image being written.
        path: String,
        /// What failed.
        message: String,
    },
}

/// The largest file a plot reads, bytes (a trace of 4 GiB is some 40 million rows, far beyond
/// what a figure can show); non-regular files (`/dev/zero`, pipes) are refused.
pub const MAX_INPUT_BYTES: u64 = 4 << 30;

/// Opens `path` for a streaming reader after checking it is a regular file; at most
/// [`MAX_INPUT_BYTES`] are read from it, counted on the bytes read (a `/proc` file declares 0
/// bytes), and a read past them is an error.
pub(crate) fn open_input(
    path: &std::path::Path,
) -> Result<isotrack_fields::io::LimitedReader, PlotError> {
    isotrack_fields::io::open_limited(path, MAX_INPUT_BYTES)
        .map_err(|e| PlotError::Input(format!("{}: {e}", path.display())))
}

/// Registers the bundled font (idempotent).
pub(crate) fn fonts() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
        for style in [
            plotters::style::FontStyle::Normal,
            plotters::style::FontStyle::Bold,
            plotters::style::FontStyle::Italic,
            plotters::style::FontStyle::Oblique,
        ] {
            // The font is valid (a test checks rendering); a failure would only lose labels.
            for family in ["sans-serif", crate::style::DEFAULT_FONT_FAMILY] {
                let _ = plotters::style::register_font(family, style, FONT);
            }
        }
    });
}
