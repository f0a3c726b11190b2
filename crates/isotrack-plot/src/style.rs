//! How a figure looks: format, size, fonts, title, colour map, resolution; and the tick labels.

use plotters::prelude::*;
use plotters::style::colors::colormaps::{BlackWhite, Bone, Copper, ViridisRGB};

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
            for family in ["sans-serif", DEFAULT_FONT_FAMILY] {
                let _ = plotters::style::register_font(family, style, FONT);
            }
        }
    });
}

/// The font family written into figures: DejaVu Sans (bundled, and used to lay text out), then
/// common fallbacks for SVG viewers that lack it.
pub const DEFAULT_FONT_FAMILY: &str = "DejaVu Sans, Helvetica, Arial, sans-serif";

/// The colour map of heat maps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Colormap {
    /// Viridis (perceptually uniform, colour-blind safe; the default).
    #[default]
    Viridis,
    /// Black to white (prints in grey scale).
    Gray,
    /// Bone (grey with a blue cast).
    Bone,
    /// Copper.
    Copper,
}

impl Colormap {
    /// Parses `viridis`, `gray` (or `grey`), `bone`, `copper`.
    pub fn from_name(name: &str) -> Option<Self> {
        match name.to_ascii_lowercase().as_str() {
            "viridis" => Some(Self::Viridis),
            "gray" | "grey" => Some(Self::Gray),
            "bone" => Some(Self::Bone),
            "copper" => Some(Self::Copper),
            _ => None,
        }
    }

    /// The colour of `v` on `[lo, hi]`.
    pub fn colour(self, v: f64, lo: f64, hi: f64) -> RGBColor {
        match self {
            Self::Viridis => ViridisRGB::get_color_normalized(v, lo, hi),
            Self::Gray => BlackWhite::get_color_normalized(v, lo, hi),
            Self::Bone => Bone::get_color_normalized(v, lo, hi),
            Self::Copper => Copper::get_color_normalized(v, lo, hi),
        }
    }
}

/// Figure options (`--size`, `--font-size`, `--title`, `--colormap`, `--dpi` on `plot`, `run
/// --plot` and `figures`). Sizes are in pixels at 100 dpi; `dpi` scales every pixel dimension of
/// a PNG (fonts and lines included), so `--dpi 300` gives a print-resolution image of the same
/// layout.
#[derive(Clone, Debug, PartialEq)]
pub struct Style {
    /// PNG or SVG.
    pub format: Format,
    /// Width x height in pixels at 100 dpi (default per figure: 1100 x 900 for maps in PNG;
    /// SVG figures default to about half, sized for a single journal column, so their text stays
    /// readable when scaled to 8.5 cm).
    pub size_px: Option<(u32, u32)>,
    /// Base font size, px at 100 dpi (default 16 for PNG, 13 for SVG); titles and labels scale
    /// with it.
    pub font_px: Option<f64>,
    /// Replaces the figure's title (an empty string: no title).
    pub title: Option<String>,
    /// Heat-map colours.
    pub colormap: Colormap,
    /// PNG resolution, dots per inch (default 100).
    pub dpi: f64,
    /// The font family: [`DEFAULT_FONT_FAMILY`] (text is laid out with the bundled DejaVu Sans
    /// whatever the name).
    pub font_family: String,
}

impl Style {
    /// The defaults for `format`.
    pub fn new(format: Format) -> Self {
        Self {
            format,
            size_px: None,
            font_px: None,
            title: None,
            colormap: Colormap::Viridis,
            dpi: 100.0,
            font_family: DEFAULT_FONT_FAMILY.into(),
        }
    }

    /// The resolution factor: `dpi/100` for PNG (within 0.25..8), 1 for SVG (vector): output
    /// pixels per pixel at 100 dpi.
    pub fn scale(&self) -> f64 {
        match self.format {
            Format::Png => (self.dpi / 100.0).clamp(0.25, 8.0),
            Format::Svg => 1.0,
        }
    }

    /// [`Style::scale`], short for the drawing code.
    pub(crate) fn k(&self) -> f64 {
        self.scale()
    }

    /// A length of `v` px at 100 dpi, in output pixels.
    pub(crate) fn px(&self, v: f64) -> u32 {
        (v * self.k()).round().max(1.0) as u32
    }

    /// The base font size, output pixels.
    pub(crate) fn base_font(&self) -> f64 {
        let default = match self.format {
            Format::Png => 16.0,
            Format::Svg => 13.0,
        };
        self.font_px.unwrap_or(default).clamp(4.0, 200.0) * self.k()
    }

    /// A font `rel` times the base size.
    pub(crate) fn font(&self, rel: f64) -> (FontFamily<'_>, f64) {
        // Only the bundled font is registered: another name would lose the text, so it is
        // used for names it was registered under and the default list otherwise.
        let family = if self.font_family == "sans-serif" || self.font_family == DEFAULT_FONT_FAMILY
        {
            self.font_family.as_str()
        } else {
            DEFAULT_FONT_FAMILY
        };
        (FontFamily::Name(family), self.base_font() * rel)
    }

    /// The output size in pixels for a figure whose default is `png` (halved and so on for
    /// SVG as `svg`), after `--size` and `--dpi`.
    pub(crate) fn size(&self, png: (u32, u32), svg: (u32, u32)) -> (u32, u32) {
        let (w, h) = self.size_px.unwrap_or(match self.format {
            Format::Png => png,
            Format::Svg => svg,
        });
        (self.px(w as f64).max(200), self.px(h as f64).max(150))
    }

    /// The title to draw: `--title` when given, else `default`.
    pub(crate) fn title<'a>(&'a self, default: &'a str) -> &'a str {
        self.title.as_deref().unwrap_or(default)
    }
}

/// Whether XML 1.0 forbids `c` in a document, even escaped (its `Char` production): the C0
/// controls but tab, newline and carriage return, and U+FFFE, U+FFFF.
pub(crate) fn forbidden_in_xml(c: char) -> bool {
    // Also DEL, the C1 controls (NEL), and the bidirectional and zero-width format characters
    // (issue 30): allowed by XML, but in a figure's text they reorder or hide what is drawn.
    matches!(c, '\u{0}'..='\u{8}' | '\u{b}' | '\u{c}' | '\u{e}'..='\u{1f}' | '\u{7f}'..='\u{9f}'
        | '\u{200b}'..='\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}' | '\u{feff}'
        | '\u{fffe}' | '\u{ffff}')
}

/// Rewrites the SVG file plotters wrote at `path` with every character XML forbids
/// ([`forbidden_in_xml`]) replaced by U+FFFD: a `--title` or a run directory name holding
/// `\x01` would otherwise make a file that is not well-formed XML (plotters writes text as
/// it is, escaping only `<>&"'`). Leaves the file alone when it holds none.
pub(crate) fn svg_without_controls(path: &std::path::Path) -> Result<(), String> {
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    if !text.chars().any(forbidden_in_xml) {
        return Ok(());
    }
    let clean: String = text
        .chars()
        .map(|c| if forbidden_in_xml(c) { '\u{fffd}' } else { c })
        .collect();
    std::fs::write(path, clean).map_err(|e| e.to_string())
}

/// A tick label: the value at a precision that tells neighbouring ticks `step` apart, without a
/// trailing `.0` and without `-0` (paper figures print `5`, `0.25`, `-3`, never `5.0` or `-0.0`).
/// A value within a millionth of a step of zero is the zero tick and reads `0` (att49-2: the
/// middle tick of a +-1e100 axis, -1e100 + 5 x 2e99 in `f64`, read `2e84`).
pub fn tick_label(v: f64, step: f64) -> String {
    if !v.is_finite() {
        return String::new();
    }
    let step = step.abs();
    if v.abs() <= 1e-6 * step {
        return "0".into();
    }
    let mag = v.abs().max(step);
    if mag != 0.0 && !(1e-4..1e6).contains(&mag) {
        // Scientific, with the digits the step needs.
        let digits = if step > 0.0 {
            ((mag / step).log10().ceil().max(0.0) as usize).min(12)
        } else {
            3
        };
        let t = format!("{:.*e}", digits, v);
        return trim_sci(&t);
    }
    let decimals = if step > 0.0 {
        ((-step.log10()).ceil().max(0.0) as usize + 1).min(15)
    } else {
        3
    };
    let t = format!("{:.*}", decimals, v);
    let t = if t.contains('.') {
        t.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        t
    };
    if t == "-0" {
        "0".into()
    } else {
        t
    }
}

/// `1.500e3` -> `1.5e3`, `2.000e-5` -> `2e-5`.
fn trim_sci(t: &str) -> String {
    match t.split_once('e') {
        Some((m, e)) => {
            let m = if m.contains('.') {
                m.trim_end_matches('0').trim_end_matches('.')
            } else {
                m
            };
            let m = if m == "-0" { "0" } else { m };
            format!("{m}e{e}")
        }
        None => t.to_string(),
    }
}

/// A value as the user wrote it (a level, a setting): the shortest decimal that reads back
/// as the same `f64`, in scientific notation outside `[1e-4, 1e6)` (as [`tick_label`]).
pub fn value_label(v: f64) -> String {
    let mag = v.abs();
    if mag != 0.0 && mag.is_finite() && !(1e-4..1e6).contains(&mag) {
        format!("{v:e}")
    } else if v == 0.0 {
        "0".into()
    } else {
        format!("{v}")
    }
}

/// The spacing of about `n` ticks over `[lo, hi]` (a 1, 2 or 5 times a power of ten), which
/// [`tick_label`] needs to pick its precision.
pub fn tick_step(lo: f64, hi: f64, n: usize) -> f64 {
    let raw = (hi - lo).abs() / n.max(1) as f64;
    if !(raw.is_finite() && raw > 0.0) {
        return 0.0;
    }
    let p = 10f64.powf(raw.log10().floor());
    let m = raw / p;
    p * if m < 1.5 {
        1.0
    } else if m < 3.5 {
        2.0
    } else if m < 7.5 {
        5.0
    } else {
        10.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_paper_ready() {
        assert_eq!(tick_label(5.0, 1.0), "5");
        assert_eq!(tick_label(-0.0, 1.0), "0");
        assert_eq!(tick_label(-1e-17, 0.5), "0");
        assert_eq!(tick_label(0.25, 0.05), "0.25");
        assert_eq!(tick_label(-3.0, 1.0), "-3");
        assert_eq!(tick_label(600.0, 100.0), "600");
        // A nearly flat field: ticks 1e-4 apart stay distinct.
        assert_eq!(tick_label(10.0001, 0.0001), "10.0001");
        assert_ne!(tick_label(10.0001, 0.0001), tick_label(10.0002, 0.0001));
        assert_eq!(tick_label(1.5e7, 5e6), "1.5e7");
        assert_eq!(tick_label(2e-5, 1e-5), "2e-5");
        assert_eq!(tick_step(0.0, 600.0, 10), 50.0);
        assert_eq!(tick_step(10.0, 10.001, 10), 1e-4);
    }

    /// att49-2: the zero tick of a +-1e100 axis (plotters steps to it by repeated addition)
    /// carries rounding noise, 2e84 on a 2e99 step, as seen; it reads `0`.
    #[test]
    fn the_zero_tick_of_a_huge_axis_reads_zero() {
        let step = tick_step(-1.16e100, 1.16e100, 8);
        assert_eq!(step, 2e99);
        assert_eq!(tick_label(2e84, step), "0");
        assert_eq!(tick_label(-2e84, step), "0");
        let mut v = -1.2e100;
        for _ in 0..6 {
            v += step;
        }
        assert_eq!(tick_label(v, step), "0", "{v:e}");
        assert_eq!(tick_label(-2e99, step), "-2e99");
        assert_eq!(tick_label(-1e100, step), "-1e100");
        // Small axes are unchanged: a tick a step from zero is not zero.
        assert_eq!(tick_label(1e-6, 1e-6), "1e-6");
    }

    /// A level reads back as written, however many digits (a tick label would round
    /// -12344.9995 to -12344.999 and 0.0001 to 0).
    #[test]
    fn value_labels_keep_every_digit() {
        assert_eq!(value_label(10.0), "10");
        assert_eq!(value_label(3.0), "3");
        assert_eq!(value_label(-12344.9995), "-12344.9995");
        assert_eq!(value_label(0.0001), "0.0001");
        assert_eq!(value_label(12345.1), "12345.1");
        assert_eq!(value_label(-0.0), "0");
        assert_eq!(value_label(2.5e-7), "2.5e-7");
        assert_eq!(value_label(1.5e7), "1.5e7");
        assert_eq!(value_label(0.1 + 0.2), "0.30000000000000004");
    }
}
