//! The controllers a benchmark scores: the built-in laws by name, and your own.
//!
//! Your own law, from Rust: implement [`IsolineController`] (it receives only
//! `Measurement { t_s, value }`) and register a factory, one line:
//!
//! ```
//! use isotrack_league::Registry;
//! use isotrack_core::{IsolineController, Measurement};
//!
//! /// omega = k * (s - s_d): a bare proportional law.
//! struct Proportional { level: f64, k: f64 }
//! impl IsolineController for Proportional {
//!     fn update(&mut self, m: &Measurement) -> f64 { self.k * (m.value - self.level) }
//!     fn reset(&mut self) {}
//! }
//!
//! let mut registry = Registry::builtin();
//! registry
//!     .register("my_proportional", |s: &isotrack_scenario::Scenario| {
//!         Box::new(Proportional { level: s.level(), k: 0.5 }) as Box<dyn IsolineController + Send>
//!     })
//!     .expect("a name of its own");
//! assert!(registry.get("my_proportional").is_some());
//! // A built-in law's name is refused: its row would show your scores.
//! let copy = |s: &isotrack_scenario::Scenario| {
//!     Box::new(Proportional { level: s.level(), k: 0.5 }) as Box<dyn IsolineController + Send>
//! };
//! assert!(registry.register("pi_isoline", copy).is_err());
//! ```
//!
//! A name must be usable as a leaderboard row ([`check_name`]): not empty, at most
//! [`MAX_NAME_CHARS`] characters, no leading or trailing whitespace, no `|`, line break or
//! control character (they break the Markdown table and the CSV), and not a built-in law's name
//! in any case (`PI_Isoline` would pass for `pi_isoline`).
//!
//! The factory gets each run's scenario (its level `s_d`, turn-rate limit, ... but never the
//! vehicle's position: the controller itself sees only the measurements). The benchmark clips its
//! command to the scenario's turn-rate limit as the built-in laws' output stage does. A
//! registered controller is scored with the gains its factory gives (the built-in laws are
//! tuned; yours is what you made it).

use isotrack_core::{IsolineController, Measurement};
use isotrack_scenario::schema::ControllerKind;
use isotrack_scenario::Scenario;
use std::sync::Arc;

/// Makes a controller for one run.
pub trait ControllerFactory: Send + Sync {
    /// A fresh controller for a run of `scenario`.
    fn make(&self, scenario: &Scenario) -> Box<dyn IsolineController + Send>;
}

impl<F> ControllerFactory for F
where
    F: Fn(&Scenario) -> Box<dyn IsolineController + Send> + Send + Sync,
{
    fn make(&self, scenario: &Scenario) -> Box<dyn IsolineController + Send> {
        self(scenario)
    }
}

/// A controller a benchmark can score.
#[derive(Clone)]
pub enum Entrant {
    /// A built-in law (`controller.kind`), tuned per task.
    Builtin(ControllerKind),
    /// A registered controller, scored as its factory makes it.
    Custom(Arc<dyn ControllerFactory>),
}

/// Named controllers.
#[derive(Clone, Default)]
pub struct Registry {
    entries: Vec<(String, Entrant)>,
}

impl Registry {
    /// The built-in coordinate-free laws (and `gradient_reference`, which is not coordinate-free
    /// and is scored only when a suite names it).
    pub fn builtin() -> Self {
        Self {
            entries: ControllerKind::ALL
                .iter()
                .map(|k| (k.name().to_string(), Entrant::Builtin(*k)))
                .collect(),
        }
    }

    /// Registers a controller under `name`, replacing one registered before under the same
    /// name. Refuses a name [`check_name`] refuses (a built-in law's, an empty one, one that
    /// breaks the leaderboard's Markdown or CSV): the registry is then unchanged.
    pub fn register(
        &mut self,
        name: &str,
        factory: impl ControllerFactory + 'static,
    ) -> Result<(), NameError> {
        check_name(name)?;
        self.entries.retain(|(n, _)| n != name);
        self.entries
            .push((name.to_string(), Entrant::Custom(Arc::new(factory))));
        Ok(())
    }

    /// The controller named `name`.
    pub fn get(&self, name: &str) -> Option<&Entrant> {
        self.entries.iter().find(|(n, _)| n == name).map(|(_, e)| e)
    }

    /// Every name, built-in first, in registration order.
    pub fn names(&self) -> Vec<&str> {
        self.entries.iter().map(|(n, _)| n.as_str()).collect()
    }

    /// The registered (not built-in) names.
    pub fn custom_names(&self) -> Vec<&str> {
        self.entries
            .iter()
            .filter(|(_, e)| matches!(e, Entrant::Custom(_)))
            .map(|(n, _)| n.as_str())
            .collect()
    }
}

/// The longest name a registered controller may have, characters.
pub const MAX_NAME_CHARS: usize = 64;

/// Why a name cannot be registered ([`Registry::register`], [`check_name`]).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum NameError {
    /// The name is empty.
    #[error("controller name is empty: give your controller a name for its leaderboard row")]
    Empty,
    /// The name is a built-in law's (compared ignoring case).
    #[error("controller name {0:?} is the name of the built-in law {1:?}: the leaderboard would show your scores as the built-in law's; choose another name")]
    Builtin(String, &'static str),
    /// The name is longer than [`MAX_NAME_CHARS`].
    #[error("controller name of {0} characters: at most {max}", max = MAX_NAME_CHARS)]
    TooLong(usize),
    /// The name holds a character that breaks a leaderboard table.
    #[error("controller name {0:?} contains {1:?}: names are rows of Markdown and CSV tables; use no '|', line breaks, control or invisible (zero-width) characters")]
    BadChar(String, char),
    /// The name starts or ends with whitespace (it would pass for another name).
    #[error("controller name {0:?} starts or ends with whitespace")]
    Whitespace(String),
}

/// Checks a name for a registered controller: what [`Registry::register`] refuses.
pub fn check_name(name: &str) -> Result<(), NameError> {
    let n = name.chars().count();
    if n == 0 {
        return Err(NameError::Empty);
    }
    if n > MAX_NAME_CHARS {
        return Err(NameError::TooLong(n));
    }
    // Invisible characters (a zero-width space, a bidi control) make a name that prints as
    // another: `pi_isoline\u{200b}` would show as a second `pi_isoline` row.
    // The one plain-text rule (numtext::is_not_plain: controls, format characters, line and
    // paragraph separators, invisibles), and `|`, a Markdown table's cell separator.
    let breaks = |c: char| c == '|' || isotrack_core::numtext::is_not_plain(c);
    if let Some(c) = name.chars().find(|&c| breaks(c)) {
        return Err(NameError::BadChar(name.to_string(), c));
    }
    if name.trim() != name {
        return Err(NameError::Whitespace(name.to_string()));
    }
    if let Some(k) = ControllerKind::ALL
        .iter()
        .find(|k| k.name().eq_ignore_ascii_case(name))
    {
        return Err(NameError::Builtin(name.to_string(), k.name()));
    }
    Ok(())
}

/// A registered controller behind the turn-rate limit of its run (the built-in laws' output
/// stage does the same for them).
pub(crate) struct Clipped {
    pub(crate) inner: Box<dyn IsolineController + Send>,
    pub(crate) max_turn_rate_radps: Option<f64>,
}

impl IsolineController for Clipped {
    fn update(&mut self, m: &Measurement) -> f64 {
        let w = self.inner.update(m);
        match self.max_turn_rate_radps {
            Some(l) => w.clamp(-l, l),
            None => w,
        }
    }
    fn reset(&mut self) {
        self.inner.reset()
    }
}
