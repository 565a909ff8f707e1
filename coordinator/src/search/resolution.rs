//! Multi-resolution bootstrapping (paper §III): evaluate at a coarse resolution first and move to
//! the next finer one when progress stalls, or at the latest after a set number of evaluations
//! (a coarse level that keeps improving slowly would otherwise spend the budget on a design the
//! fine grid scores far worse: docs/evolution.md, session 9).

use amorph::voxel::GridDims;

use super::island::Island;
use super::stall::Stall;
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ResolutionSchedule {
    /// Resolutions from coarse to fine, as [nx, ny, nz].
    pub levels: Vec<[usize; 3]>,
    /// Epochs without enough improvement of the run's best fitness before moving to the next level.
    #[serde(default = "default_stall_epochs")]
    pub stall_epochs: usize,
    /// Improvement that counts as progress, relative to the best fitness's magnitude.
    #[serde(default = "default_min_improvement")]
    pub min_improvement: f64,
    /// For each level but the last, the run's evaluations by which it gives way to the next one,
    /// stalled or not. Empty (the default): only the stall rule.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub latest_switch: Vec<u64>,
    /// At a switch, the islands become one island of `population` and its epochs breed all the
    /// islands' children: the designs re-evaluated at the finer level are each island's best, then
    /// each one's second best, and so on, instead of every island's whole population. Default
    /// false (every island re-evaluated and kept). Many small islands explore the coarse grid
    /// well but arrive at the fine one barely bred (docs/evolution.md, session 17).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub merge_islands: bool,
    /// The merged island's population, when it should not be `search.population`: islands that
    /// split one population (sixteen of 3) merge back into its whole (48), not into one island's
    /// 3. Unset (the default): `search.population`. Needs `merge_islands`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub merged_population: Option<usize>,
    /// At a coarse level, the run's best design is also evaluated at the finest level whenever it
    /// changes (one evaluation each), and the stall rule watches the best of those scores instead
    /// of the coarse fitness: a coarse level gives way once it stops finding designs that are
    /// better on the fine grid. Default false (the coarse fitness, the paper's rule). A coarse
    /// level's climbed best can score far worse on the fine grid (docs/evolution.md, session 19).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub stall_on_finest: bool,
    /// With `stall_on_finest`: at the switch to the finest level, the design the checks ranked
    /// best joins the island that held it when checked, in place of that island's worst
    /// re-evaluated individual (only if fitter, and only if the island no longer holds it). Its
    /// check is its evaluation there, so it costs nothing. Default false (the switch re-evaluates
    /// the populations alone). The coarse level climbs on after its best check and can leave that
    /// design behind: in 14 circular-arc runs of session 34 the re-evaluated populations' best was
    /// up to 1.7 times the best check's error (docs/evolution.md).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub carry_checked_best: bool,
    /// With `stall_on_finest`: each check at the finest level is sent out together with the
    /// next epoch's children, which do not depend on it; they are kept unless the check ends
    /// the level (then they are dropped unstored, and the run is as if they were never bred).
    /// The results are the same bits either way; only the wall time differs. Default true.
    /// Written out even at its default, so a run store says whether its run overlapped (the
    /// wall model reads it; stores from before the key read as not).
    #[serde(default = "default_overlap_finest_checks")]
    pub overlap_finest_checks: bool,
}

fn default_stall_epochs() -> usize {
    10
}
fn default_min_improvement() -> f64 {
    0.02
}
fn default_overlap_finest_checks() -> bool {
    true
}

impl ResolutionSchedule {
    pub fn single(dims: GridDims) -> Self {
        Self {
            levels: vec![[dims.nx, dims.ny, dims.nz]],
            stall_epochs: default_stall_epochs(),
            min_improvement: default_min_improvement(),
            latest_switch: Vec::new(),
            merge_islands: false,
            merged_population: None,
            stall_on_finest: false,
            carry_checked_best: false,
            overlap_finest_checks: true,
        }
    }

    pub fn dims(&self, level: usize) -> GridDims {
        let [nx, ny, nz] = self.levels[level];
        GridDims::new(nx, ny, nz)
    }

    /// The finest resolution, the last level.
    pub fn finest(&self) -> GridDims {
        self.dims(self.levels.len() - 1)
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.levels.is_empty() {
            return Err("resolution.levels must list at least one resolution".into());
        }
        for (i, l) in self.levels.iter().enumerate() {
            amorph_proto::grid::checked_grid(l.map(|n| n as u64))
                .map_err(|e| format!("resolution.levels[{i}] = {l:?}: {e}"))?;
        }
        if !(self.min_improvement.is_finite() && self.min_improvement >= 0.0) {
            return Err("resolution.min_improvement must be a non-negative number".into());
        }
        match self.merged_population {
            Some(n @ (0 | 1)) => {
                return Err(format!(
                    "resolution.merged_population = {n} must be at least 2 (crowding needs two to compare)"
                ));
            }
            Some(n) if !self.merge_islands => {
                return Err(format!(
                    "resolution.merged_population = {n} needs resolution.merge_islands = true (without it the islands never merge)"
                ));
            }
            _ => {}
        }
        if self.carry_checked_best && !self.stall_on_finest {
            return Err("resolution.carry_checked_best = true needs resolution.stall_on_finest = true (without it nothing is checked at the finest level to carry)".into());
        }
        let l = &self.latest_switch;
        if !l.is_empty() && l.len() + 1 != self.levels.len() {
            return Err(format!(
                "resolution.latest_switch lists {} evaluation counts: it needs one per level but the last ({})",
                l.len(),
                self.levels.len() - 1
            ));
        }
        if let Some(i) = (1..l.len()).find(|&i| l[i] <= l[i - 1]) {
            return Err(format!(
                "resolution.latest_switch[{i}] = {} must be larger than the one before it ({})",
                l[i],
                l[i - 1]
            ));
        }
        Ok(())
    }
}

/// Tracks stalls and decides when to switch level. A pure function of the best-fitness sequence,
/// so the switch happens at the same epoch in every run with the same seed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResolutionState {
    pub level: usize,
    stall: Stall,
}

impl ResolutionState {
    pub fn new() -> Self {
        Self {
            level: 0,
            stall: Stall::new(),
        }
    }

    /// Records the best fitness after an epoch that brought the run to `evaluations`; returns true
    /// when the run should move to the next level (and then resets the stall tracking for it).
    pub fn observe(&mut self, best: f64, evaluations: u64, schedule: &ResolutionSchedule) -> bool {
        let stalled = self.stall.observe(best, schedule.min_improvement);
        let overdue = schedule
            .latest_switch
            .get(self.level)
            .is_some_and(|&latest| evaluations >= latest);
        if self.level + 1 < schedule.levels.len() && (stalled >= schedule.stall_epochs || overdue) {
            self.level += 1;
            self.stall = Stall::new();
            return true;
        }
        false
    }

    /// Whether the run is at its finest resolution.
    pub fn is_final(&self, schedule: &ResolutionSchedule) -> bool {
        self.level + 1 == schedule.levels.len()
    }
}

/// The individuals that carry merged islands into the next level, as (island, slot): every
/// island's best (in island order), then every island's second best, and so on, `count` in all,
/// passing over a genome already taken. Taking ranks in turn rather than the pool's fittest keeps
/// one island's near-copies of its best from filling the merged population, and passing over
/// repeats keeps migrants' copies out (in a 16-island run a third of the islands' bests were
/// copies of one another: docs/evolution.md, session 18). Only when fewer than `count` genomes
/// differ are repeats taken, in the same order.
pub fn merge_order(islands: &[Island], count: usize) -> Vec<(usize, usize)> {
    let ranked: Vec<Vec<usize>> = islands.iter().map(Island::ranked_slots).collect();
    let deepest = ranked.iter().map(Vec::len).max().unwrap_or(0);
    let turns: Vec<(usize, usize)> = (0..deepest)
        .flat_map(|rank| {
            ranked
                .iter()
                .enumerate()
                .filter_map(move |(i, order)| order.get(rank).map(|&slot| (i, slot)))
        })
        .collect();
    let genome = |&(i, s): &(usize, usize)| &islands[i].population[s].genome;
    let (mut chosen, mut repeats) = (Vec::new(), Vec::new());
    for turn in turns {
        if chosen.len() == count {
            break;
        }
        if chosen.iter().any(|c| genome(c) == genome(&turn)) {
            repeats.push(turn);
        } else {
            chosen.push(turn);
        }
    }
    chosen.extend(repeats);
    chosen.truncate(count);
    chosen
}

impl Default for ResolutionState {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn switches_after_the_configured_stall() {
        let schedule = ResolutionSchedule {
            levels: vec![[1, 2, 1], [2, 4, 2]],
            stall_epochs: 3,
            min_improvement: 0.1,
            latest_switch: vec![],
            merge_islands: false,
            merged_population: None,
            stall_on_finest: false,
            carry_checked_best: false,
            overlap_finest_checks: true,
        };
        let mut s = ResolutionState::new();
        assert!(!s.observe(-10.0, 10, &schedule));
        assert!(!s.observe(-5.0, 20, &schedule)); // progress
        assert!(!s.observe(-4.8, 30, &schedule)); // under 10 %: stall 1
        assert!(!s.observe(-4.7, 40, &schedule)); // stall 2
        assert!(s.observe(-4.7, 50, &schedule)); // stall 3: switch
        assert_eq!(s.level, 1);
        for _ in 0..10 {
            assert!(!s.observe(-1.0, 60, &schedule), "no level beyond the last");
        }
    }

    /// A level that keeps improving never stalls; `latest_switch` moves on anyway, once per level
    /// and at the first epoch that reaches the count, and never past the last level.
    #[test]
    fn a_level_that_keeps_improving_gives_way_at_its_latest_switch() {
        let schedule = ResolutionSchedule {
            levels: vec![[1, 2, 1], [2, 4, 2], [3, 6, 3]],
            stall_epochs: 3,
            min_improvement: 0.01,
            latest_switch: vec![100, 250],
            merge_islands: false,
            merged_population: None,
            stall_on_finest: false,
            carry_checked_best: false,
            overlap_finest_checks: true,
        };
        let mut s = ResolutionState::new();
        let mut best = -100.0;
        let mut switched_at = Vec::new();
        for evaluations in (10..=400).step_by(10) {
            best *= 0.9; // 10 % better every epoch: never a stall
            if s.observe(best, evaluations, &schedule) {
                switched_at.push(evaluations);
            }
        }
        assert_eq!(switched_at, [100, 250]);
        assert_eq!(s.level, 2);
    }

    #[test]
    fn latest_switch_needs_one_increasing_count_per_coarse_level() {
        let schedule = |latest_switch: Vec<u64>| ResolutionSchedule {
            levels: vec![[1, 2, 1], [2, 4, 2], [3, 6, 3]],
            stall_epochs: 3,
            min_improvement: 0.01,
            latest_switch,
            merge_islands: false,
            merged_population: None,
            stall_on_finest: false,
            carry_checked_best: false,
            overlap_finest_checks: true,
        };
        assert!(schedule(vec![]).validate().is_ok());
        assert!(schedule(vec![100, 200]).validate().is_ok());
        let err = schedule(vec![100]).validate().unwrap_err();
        assert!(err.starts_with("resolution.latest_switch lists 1"), "{err}");
        let err = schedule(vec![200, 200]).validate().unwrap_err();
        assert!(
            err.starts_with("resolution.latest_switch[1] = 200"),
            "{err}"
        );
    }

    /// Ranks are taken in turn across islands, ties keep slot order, a failed design (ranked
    /// last) comes after every scored one of its island, an island smaller than the others
    /// simply runs out, and a genome already taken (a migrant's copy) waits until every distinct
    /// one is in.
    #[test]
    fn merging_takes_every_islands_best_then_every_second_best() {
        use crate::search::fixtures::{failed, island};
        let mut a = island(0, &[0.1, 0.2, 0.3], &[-3.0, -1.0, -2.0]);
        a.population[0].outcome = failed();
        let b = island(1, &[0.4, 0.5], &[-0.5, -0.5]);
        let c = island(2, &[0.6, 0.7, 0.8], &[-9.0, -4.0, -7.0]);
        let mut islands = [a, b, c];
        // Each carried individual as "island slot".
        let order = |islands: &[Island], count| {
            let taken: Vec<String> = (merge_order(islands, count).iter())
                .map(|(i, s)| format!("{i}{s}"))
                .collect();
            taken.join(" ")
        };
        assert_eq!(order(&islands, 8), "01 10 21 02 11 22 00 20");
        assert_eq!(order(&islands, 4), "01 10 21 02");
        assert_eq!(order(&islands, 20), order(&islands, 8));
        // Island 2's best is a copy of island 0's: it goes after the seven distinct genomes.
        islands[2].population[1].genome = islands[0].population[1].genome.clone();
        assert_eq!(order(&islands, 8), "01 10 02 11 22 00 20 21");
        assert_eq!(order(&islands, 3), "01 10 02");
    }

    #[test]
    fn merged_population_needs_a_merge_and_two_individuals() {
        let schedule = |merge_islands, merged_population| ResolutionSchedule {
            merge_islands,
            merged_population,
            ..ResolutionSchedule::single(GridDims::new(1, 2, 1))
        };
        assert!(schedule(true, Some(48)).validate().is_ok());
        assert!(schedule(false, None).validate().is_ok());
        let err = schedule(false, Some(48)).validate().unwrap_err();
        assert!(
            err.starts_with("resolution.merged_population = 48 needs resolution.merge_islands"),
            "{err}"
        );
        let err = schedule(true, Some(1)).validate().unwrap_err();
        assert!(
            err.starts_with("resolution.merged_population = 1 must be at least 2"),
            "{err}"
        );
    }

    #[test]
    fn carrying_the_checked_best_needs_the_checks() {
        let schedule = |stall_on_finest, carry_checked_best| ResolutionSchedule {
            stall_on_finest,
            carry_checked_best,
            ..ResolutionSchedule::single(GridDims::new(1, 2, 1))
        };
        assert!(schedule(true, true).validate().is_ok());
        assert!(schedule(false, false).validate().is_ok());
        let err = schedule(false, true).validate().unwrap_err();
        assert!(
            err.starts_with(
                "resolution.carry_checked_best = true needs resolution.stall_on_finest"
            ),
            "{err}"
        );
    }
}
