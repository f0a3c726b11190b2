//! The error every grid loader returns: the file, where in it (line or byte offset), and what
//! is wrong.

use crate::grid::GridError;
use std::fmt;
use std::path::Path;

/// Where in a file a problem is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FilePosition {
    /// 1-based line (text formats), with an optional 1-based field/column.
    Line(usize, Option<usize>),
    /// Byte offset (binary formats).
    Offset(u64),
}

/// A grid file that cannot be used.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoadError {
    /// The file.
    pub path: String,
    /// Where in it, if known.
    pub position: Option<FilePosition>,
    /// What is wrong.
    pub message: String,
    /// The file itself could not be read (missing, not a regular file, no permission, beyond
    /// the size limit), as opposed to what it holds: exit 66 rather than 65 (README, "Exit
    /// codes").
    pub unreadable: bool,
}

/// Shown on one line, whatever the file holds: the path and the message (which quotes names,
/// units and headers read from the file, and the reader crates' errors) are [`Escaped`], so a
/// line feed or a terminal control in them is shown as `\x0a` / `\x1b` (issue 30).
///
/// [`Escaped`]: isotrack_core::numtext::Escaped
impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use isotrack_core::numtext::Escaped;
        let (path, message) = (Escaped(&self.path), Escaped(&self.message));
        match &self.position {
            Some(FilePosition::Line(l, Some(c))) => {
                write!(f, "{path}:{l}: field {c}: {message}")
            }
            Some(FilePosition::Line(l, None)) => write!(f, "{path}:{l}: {message}"),
            Some(FilePosition::Offset(o)) => {
                write!(f, "{path} (byte offset {o}): {message}")
            }
            None => write!(f, "{path}: {message}"),
        }
    }
}

impl std::error::Error for LoadError {}

impl LoadError {
    pub(crate) fn new(
        path: &Path,
        position: Option<FilePosition>,
        message: impl Into<String>,
    ) -> Self {
        Self {
            path: path.display().to_string(),
            position,
            message: message.into(),
            unreadable: false,
        }
    }
    /// The file could not be read at all (see [`LoadError::unreadable`]); a file too large
    /// for the memory this process may use (an `OutOfMemory` error, from
    /// [`super::limits::read_limited`]) is refused as the Limits table's memory check is, exit
    /// 65, naming the memory (att43-5).
    pub(crate) fn cannot_read(path: &Path, e: std::io::Error) -> Self {
        if e.kind() == std::io::ErrorKind::OutOfMemory {
            return Self::new(path, None, format!("too large to load: {e}"));
        }
        Self {
            unreadable: true,
            ..Self::new(path, None, format!("cannot read: {e}"))
        }
    }
    pub(crate) fn grid(path: &Path, e: GridError) -> Self {
        Self::new(path, None, e.to_string())
    }
}
