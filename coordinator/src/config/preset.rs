//! Search presets: named sets of defaults for the search keys, laid under what a config writes.
//! `climb` is the best search measured on beams and their default; `paper` is Hiller & Lipson's
//! search, kept for reproduction and the default for the tasks the climb was not measured on. A
//! key the config names (or `--set` gives) always wins over its preset.

use serde::{Deserialize, Serialize};

/// `[search] preset`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// Deterministic crowding with a shared climb around the run's best design: half of every
    /// coarse epoch and all of the finest level's children are nudges or boundary insertions,
    /// an epoch's improving nudges added up, the coarse level judged on the finest grid, and
    /// children that copy their parent's design not evaluated.
    Climb,
    /// The paper's search (§II-C): deterministic crowding alone, every child evaluated.
    #[default]
    Paper,
}

const CLIMB: &str = r#"
[search]
preset = "climb"
population = 48
children_per_epoch = 48
skip_unchanged = true

[search.local_search]
fraction = 0.5
finest_fraction = 1.0
points = 1
step = 0.02
insertion = 0.5
shared = true
combine = true

[resolution]
stall_epochs = 15
stall_on_finest = true
"#;

const PAPER: &str = r#"
[search]
preset = "paper"
population = 50
children_per_epoch = 50
skip_unchanged = false

[search.local_search]
fraction = 0.0
insertion = 0.0
shared = false
combine = false

[resolution]
stall_epochs = 15
stall_on_finest = false
"#;

impl Preset {
    /// The preset a config gets when it names none: the climb for single-objective beams, where
    /// it was measured, the paper's search for every other task and for any run with several
    /// objectives (the climb follows one fitness).
    pub fn for_run(kind: &str, multi_objective: bool) -> Self {
        if kind == "beam" && !multi_objective {
            Preset::Climb
        } else {
            Preset::Paper
        }
    }

    /// The preset as the config writes it.
    pub fn key(self) -> &'static str {
        match self {
            Preset::Climb => "climb",
            Preset::Paper => "paper",
        }
    }

    /// The preset's keys, as a config document.
    pub fn defaults(self) -> toml::Table {
        let text = match self {
            Preset::Climb => CLIMB,
            Preset::Paper => PAPER,
        };
        text.parse().expect("the presets are valid TOML")
    }
}

/// Lays `defaults` under `config`: every key of `defaults` that `config` lacks is added, tables
/// merged key by key; a key `config` has keeps its value, whatever its type.
pub fn lay_under(config: &mut toml::Table, defaults: toml::Table) {
    for (key, default) in defaults {
        match (config.get_mut(&key), default) {
            (None, default) => {
                config.insert(key, default);
            }
            (Some(toml::Value::Table(table)), toml::Value::Table(default)) => {
                lay_under(table, default);
            }
            (Some(_), _) => {}
        }
    }
}

#[cfg(test)]
mod tests;
