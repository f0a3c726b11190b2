//! A problem with one key's value: what resolution, the spec and the field's files report.

/// A problem with one key's value.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Issue {
    /// Dotted key, e.g. `controller.kp`.
    pub key: String,
    /// What is wrong.
    pub message: String,
    /// A file the key names could not be read at all (missing, not a regular file, beyond its
    /// size limit): exit 66, not 65 (README, "Exit codes").
    pub unreadable: bool,
}

/// The value resolution settled for `key` (`section.name`): an [`Issue`] if it is unset.
pub(crate) fn settled<T: Clone>(v: &Option<T>, key: &str) -> Result<T, Issue> {
    v.clone().ok_or_else(|| Issue {
        key: key.to_string(),
        message: "was not settled by resolution (an internal error: please report it)".into(),
        unreadable: false,
    })
}
