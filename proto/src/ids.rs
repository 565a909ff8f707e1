//! Typed identifiers, so an island index cannot be passed where a task id is expected. Task and
//! worker ids cross the wire as integers and text; both ends convert them here, at the edge.

use serde::{Deserialize, Serialize};

/// Index of an island (a crowding population) in a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct IslandId(pub u32);

/// A task: one genome to evaluate, unique within a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct TaskId(pub u64);

impl TaskId {
    /// First id of the check tasks (a second evaluation of an outside worker's outcome). The
    /// search's own ids count up from 1 and never get near it, so checks leave them, and with them
    /// the run store's replay, exactly as a run without checks numbers them.
    pub const FIRST_CHECK: u64 = 1 << 62;

    pub fn is_check(self) -> bool {
        self.0 >= Self::FIRST_CHECK
    }
}

impl std::fmt::Display for IslandId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "island-{}", self.0)
    }
}

impl std::fmt::Display for TaskId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "task-{}", self.0)
    }
}

/// A worker's registration with one coordinator process: a serial number and the process's tag,
/// so an id handed out before a restart (or made up) is told apart from a live one. On the wire
/// it is the text `w<serial>-<tag as 6 hex digits>`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct WorkerId {
    pub serial: u64,
    pub tag: u32,
}

impl std::fmt::Display for WorkerId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "w{}-{:06x}", self.serial, self.tag)
    }
}

impl std::str::FromStr for WorkerId {
    type Err = ();

    /// Strict: exactly the form `Display` writes, so one worker has one spelling.
    fn from_str(text: &str) -> Result<Self, ()> {
        let (serial, tag) = text
            .strip_prefix('w')
            .ok_or(())?
            .split_once('-')
            .ok_or(())?;
        let digits = |s: &str, radix: u32| {
            !s.is_empty()
                && s.chars()
                    .all(|c| c.is_digit(radix) && !c.is_ascii_uppercase())
                && !(s.len() > 1 && radix == 10 && s.starts_with('0'))
        };
        if !digits(serial, 10) || tag.len() != 6 || !digits(tag, 16) {
            return Err(());
        }
        Ok(Self {
            serial: serial.parse().map_err(|_| ())?,
            tag: u32::from_str_radix(tag, 16).map_err(|_| ())?,
        })
    }
}

#[cfg(test)]
mod tests;
