//! The check's combined verdict, a leaf of `check` (the team check gives one too).

use serde::Serialize;

/// The combined verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// A guarantee applies (Prop. 1 exact condition with a stable sampled loop, or Prop. 2's
    /// bound).
    Holds,
    /// A necessary local condition fails.
    Fails,
    /// Nothing fails, but no proposition gives a guarantee here.
    NotApplicable,
}

impl Verdict {
    /// The snake_case name.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Holds => "holds",
            Verdict::Fails => "fails",
            Verdict::NotApplicable => "not_applicable",
        }
    }
}
