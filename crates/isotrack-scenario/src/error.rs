//! Why a scenario could not be loaded, and where: the located errors every scenario reader
//! ([`crate::load`], [`crate::assign`], [`crate::Scenario::derive`]) gives, and the clipping of
//! the user's text they echo.

use std::fmt;

/// Where a scenario problem is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ErrorLocation {
    /// In the scenario file, at a 1-based line and column (if known).
    File {
        /// The file as given.
        path: String,
        /// 1-based line.
        line: Option<usize>,
        /// 1-based column.
        column: Option<usize>,
    },
    /// In a `--set KEY=VALUE` argument.
    Override {
        /// The argument as given.
        arg: String,
    },
    /// In a default value (a combination the defaults alone cannot satisfy).
    Default {
        /// The file as given, or `<built-in default>`.
        origin: String,
    },
    /// In an assignment that did not come from `--set`: a sweep's `[base]`, `[grid]` or
    /// `[random]` value, a `compare --gain`; the label names it (e.g.
    /// `sweep s.toml run 3, [grid] controller.kp=1.0`).
    Assigned {
        /// Where the assignment came from and what it was.
        label: String,
    },
    /// In a value a derived scenario inherited from the scenario it was derived from (its file
    /// or its defaults).
    Inherited {
        /// The derived scenario, e.g. `sweep s.toml run 3`.
        origin: String,
    },
}

impl fmt::Display for ErrorLocation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ErrorLocation::File {
                path,
                line: Some(l),
                column: Some(c),
            } => write!(f, "{path}:{l}:{c}"),
            ErrorLocation::File {
                path,
                line: Some(l),
                column: None,
            } => write!(f, "{path}:{l}"),
            ErrorLocation::File { path, .. } => write!(f, "{path}"),
            ErrorLocation::Override { arg } => write!(f, "--set {arg}"),
            ErrorLocation::Default { origin } => write!(f, "{origin} (default value)"),
            ErrorLocation::Assigned { label } => write!(f, "{label}"),
            ErrorLocation::Inherited { origin } => {
                write!(f, "{origin} (a value of the base scenario or its default)")
            }
        }
    }
}

/// One located problem: where, which key, what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LocatedIssue {
    /// Where.
    pub location: ErrorLocation,
    /// The dotted key, if the problem belongs to one.
    pub key: Option<String>,
    /// What is wrong.
    pub message: String,
    /// A file the key names could not be read at all (missing, not a regular file, beyond its
    /// size limit): the command exits 66, not 65 ([`ScenarioError::is_unreadable_input`]).
    pub unreadable: bool,
}

impl fmt::Display for LocatedIssue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // User text (keys, `--set` arguments, quoted values) is clipped: a message stays a
        // message whatever was typed.
        let at = clip(&self.location.to_string());
        let message = clip_quoted(&self.message);
        match &self.key {
            Some(k) => write!(f, "{at}: `{}`: {message}", clip(k)),
            None => write!(f, "{at}: {message}"),
        }
    }
}

/// `message` with every backtick-quoted span clipped by [`clip`], then the whole clipped to a
/// few times [`MAX_ECHO_CHARS`].
pub(crate) fn clip_quoted(message: &str) -> String {
    let clipped: Vec<String> = message
        .split('`')
        .enumerate()
        .map(|(i, part)| {
            if i % 2 == 1 {
                clip(part)
            } else {
                part.to_string()
            }
        })
        .collect();
    let joined = clipped.join("`");
    let max = 5 * MAX_ECHO_CHARS;
    if joined.chars().count() > max {
        let head: String = joined.chars().take(max).collect();
        format!("{head}...")
    } else {
        joined
    }
}

/// Why a scenario could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("cannot read scenario file {path}: {source}")]
    Io {
        /// The path as given.
        path: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file or an override is not valid TOML, has unknown keys, wrong types or invalid values.
    #[error("invalid scenario:\n{}", .0.iter().map(|i| format!("  {i}")).collect::<Vec<_>>().join("\n"))]
    Invalid(Vec<LocatedIssue>),
}

impl ScenarioError {
    /// Whether a file could not be read at all: the scenario file itself, or a file it names
    /// (`field.path`, `field.paths`) that is missing, a FIFO, a directory, a device or beyond
    /// its size limit. Commands exit 66 for these, 65 for what a file holds.
    pub fn is_unreadable_input(&self) -> bool {
        match self {
            ScenarioError::Io { .. } => true,
            ScenarioError::Invalid(v) => v.iter().any(|i| i.unreadable),
        }
    }

    /// The located problems (empty for I/O errors).
    pub fn issues(&self) -> &[LocatedIssue] {
        match self {
            ScenarioError::Invalid(v) => v,
            ScenarioError::Io { .. } => &[],
        }
    }
}

/// The most characters of user text (a key, a value, a file's line) echoed in one message: a
/// 10 MB key once made a 20 MB error. Counted on the text as shown, escapes included.
pub const MAX_ECHO_CHARS: usize = isotrack_core::numtext::ECHO_CHARS;

/// `text` as [`isotrack_core::numtext::Clipped`] shows it: terminal controls and line feeds
/// escaped (a message raised to Python or written to a file shows them as `\x1b`, as the
/// console does), then cut to [`MAX_ECHO_CHARS`] characters of what is shown, with the number
/// left out said.
pub fn clip(text: &str) -> String {
    isotrack_core::numtext::Clipped(text).to_string()
}
