//! The state of a search between epochs and the four things that change it: the initial
//! populations, an epoch (breed, evaluate, settle, apply), migration, and the switch to the next
//! resolution. Each is a function of the seed and the outcomes alone, so a replay from the run
//! store retraces it exactly.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

use amorph::genome::Genome;
use amorph::task::{Outcome, Scene};
use amorph::voxel::GridDims;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tracing::info;

use super::batch::{evaluate_all, evaluate_settled, settle};
use super::{Result, RunContext, RunError};
use crate::config::RunConfig;
use crate::evaluator::Evaluator;
use crate::ids::{IslandId, TaskId};
use crate::search::{
    BoundarySite, Breeding, Child, Individual, Island, ResolutionState, SharedBest, SplitWatch,
    merge_order, migrate, split_island,
};
use crate::store::{EpochRecord, MigrationRecord, Purpose, RunStore, StoredEvaluation};
use crate::summary::{HistoryRow, fittest};
use crate::verification::Evaluated;

mod finest;

use finest::{Overlap, carry_checked};

pub(super) struct Search {
    pub(super) islands: Vec<Island>,
    migration_rng: ChaCha8Rng,
    pub(super) resolution: ResolutionState,
    pub(super) epoch: usize,
    pub(super) evaluations: u64,
    pub(super) next_task: u64,
    /// Outcomes of an earlier, interrupted session of this run, by task id (see [`crate::store`]).
    pub(super) replay: HashMap<TaskId, StoredEvaluation>,
    /// The last epoch that session recorded: up to it the replay must match the store exactly.
    pub(super) replay_until: Option<usize>,
    /// The evaluation count at the end of every epoch an earlier session recorded: where a
    /// session's budget ended the run inside an epoch, it bred that epoch short, and so must its
    /// replay (see `breed_children`).
    replay_epoch_evaluations: HashMap<usize, u64>,
    pub(super) clock: RunClock,
    breeding: Breeding,
    /// Children each island breeds per epoch: the configured count, times the islands merged
    /// into one at a resolution switch (`resolution.merge_islands`) or not yet split from one
    /// (`search.split_after_stall`), so the batch stays the same.
    children_per_island: usize,
    /// Islands on demand: when the one population splits into the configured islands.
    split: SplitWatch,
    /// With `resolution.stall_on_finest`: the last best genome evaluated at the finest level at
    /// this coarse level.
    finest_checked: Option<Genome>,
    /// The design those checks ranked best, scored at the finest level, with the island that
    /// held it: its rank is what the stall rule watches, and `resolution.carry_checked_best`
    /// carries it into the finest level.
    checked_best: Option<(usize, Individual)>,
    /// The level stalled with less budget left than the switch's re-evaluation: the run ends.
    pub(super) switch_unaffordable: bool,
    /// The next epoch's children, sent out beside a finest-level check
    /// (`resolution.overlap_finest_checks`) and waiting for the stall rule's verdict.
    overlap: Option<Overlap>,
}

/// Wall time of the run across sessions: what earlier sessions used plus this session's time.
pub(super) struct RunClock {
    started: Instant,
    earlier: f64,
}

impl RunClock {
    pub(super) fn seconds(&self) -> f64 {
        self.earlier + self.started.elapsed().as_secs_f64()
    }
}

impl Search {
    /// Draws and evaluates the initial populations (island i from stream i + 1 of the run seed;
    /// stream 0 drives migration), replaying what the store already holds.
    pub(super) fn start(
        config: &RunConfig,
        scene: Arc<Scene>,
        evaluator: &mut dyn Evaluator,
        ctx: &RunContext<'_>,
    ) -> Result<Self> {
        let raw = &config.raw;
        let breeding = Breeding {
            mutation: raw.search.mutation.clone(),
            variation: raw.search.variation(),
            scene,
        };
        let island_rng = |i: usize| {
            let mut rng = ChaCha8Rng::seed_from_u64(raw.seed);
            rng.set_stream(i as u64 + 1);
            rng
        };
        let mut migration_rng = ChaCha8Rng::seed_from_u64(raw.seed);
        migration_rng.set_stream(0);

        // Islands on demand start as one island holding (and breeding for) all of them.
        let on_demand = raw.search.split_after_stall > 0;
        let (islands, together) = if on_demand {
            (1, raw.search.islands)
        } else {
            (raw.search.islands, 1)
        };
        let mut rngs: Vec<ChaCha8Rng> = (0..islands).map(island_rng).collect();
        let initial: Vec<Vec<Genome>> = rngs
            .iter_mut()
            .map(|rng| {
                Island::initial_genomes(
                    rng,
                    raw.search.population * together,
                    raw.search.initial_points,
                    &breeding,
                )
            })
            .collect();
        let replay = ctx.store.evaluations()?;
        let replay_epoch_evaluations = ctx.store.epoch_evaluations()?;
        let replay_until = replay_epoch_evaluations.keys().max().copied();
        if !replay.is_empty() {
            info!(evaluations = replay.len(), last_epoch = ?replay_until, "resuming: replaying the stored run");
        }
        let mut search = Search {
            islands: Vec::new(),
            migration_rng,
            resolution: ResolutionState::new(),
            epoch: 0,
            evaluations: 0,
            next_task: 0,
            replay,
            replay_until,
            replay_epoch_evaluations,
            clock: RunClock {
                started: Instant::now(),
                earlier: ctx.store.recorded_wall_seconds()?,
            },
            breeding,
            children_per_island: raw.search.children_per_epoch * together,
            split: SplitWatch::new(raw.search.split_after_stall),
            finest_checked: None,
            checked_best: None,
            switch_unaffordable: false,
            overlap: None,
        };
        let dims = raw.resolution.dims(0);
        let outcomes = evaluate_settled(
            &mut search,
            evaluator,
            &initial,
            dims,
            Purpose::Initial,
            ctx,
        )?;
        search.islands = initial
            .into_iter()
            .zip(outcomes)
            .zip(rngs)
            .enumerate()
            .map(|(i, ((genomes, outcomes), rng))| {
                let population = genomes
                    .into_iter()
                    .zip(outcomes)
                    .map(|(genome, (task, outcome))| Individual {
                        genome,
                        outcome,
                        task,
                    })
                    .collect();
                Island::from_evaluated(IslandId(i as u32), rng, population)
            })
            .collect();
        Ok(search)
    }

    /// One epoch: every island breeds from its snapshot, all children are evaluated as one
    /// batch, and each island applies its own. The last epoch is shortened (spread over the
    /// islands) so the run ends exactly on budget. Returns each island's replacements. Children
    /// already evaluated beside a finest-level check are these very children: they are kept
    /// (stored and counted now) instead of bred again.
    pub(super) fn epoch(
        &mut self,
        config: &RunConfig,
        dims: GridDims,
        evaluator: &mut dyn Evaluator,
        ctx: &RunContext<'_>,
    ) -> Result<Vec<usize>> {
        let combine = (self.breeding.variation.local_search.combine)
            .then_some(self.breeding.scene.limits().max_points);
        let (children, genomes, batch) = match self.overlap.take() {
            Some(overlap) if overlap.dims == dims => {
                overlap.held.keep(self, ctx)?;
                (overlap.children, overlap.genomes, overlap.batch)
            }
            other => {
                if let Some(overlap) = other {
                    self.drop_overlap(overlap);
                }
                let children = self.breed_children(config, dims, self.evaluations);
                let genomes = genomes_of(&children);
                let batch = evaluate_all(self, evaluator, &genomes, dims, Purpose::Child, ctx)?;
                (children, genomes, batch)
            }
        };
        // A child's outcome decides when it would replace its dominant parent.
        let winners = |batch: &[Vec<Evaluated>]| -> Vec<Vec<bool>> {
            self.islands
                .iter()
                .zip(&children)
                .zip(batch)
                .map(|((island, children), group)| {
                    let outcomes: Vec<&Outcome> = group.iter().map(|e| &e.outcome).collect();
                    island.winners(children, &outcomes)
                })
                .collect()
        };
        let outcomes = settle(batch, &genomes, dims, evaluator, ctx, &winners)?;
        self.epoch += 1;
        Ok(self
            .islands
            .iter_mut()
            .zip(children)
            .zip(outcomes)
            .map(|((island, children), outcomes)| island.apply(children, outcomes, combine))
            .collect())
    }

    /// The children of the next epoch at `dims`, with `spent` evaluations of the budget spent
    /// before them: the islands' share of what is left, the shared climb's nudges handed to the
    /// island holding the run's best.
    fn breed_children(
        &mut self,
        config: &RunConfig,
        dims: GridDims,
        spent: u64,
    ) -> Vec<Vec<Child>> {
        let raw = &config.raw;
        let islands = self.islands.len();
        let mut left = raw
            .budget
            .evaluations
            .map_or(u64::MAX, |max| max.saturating_sub(spent));
        // A recorded epoch is bred as the session that recorded it bred it: if that session's
        // budget cut the epoch short (the run ended there and was resumed with a larger budget),
        // its recorded evaluations say how short; otherwise they leave room for every child and
        // change nothing.
        if let Some(&recorded) = self.replay_epoch_evaluations.get(&(self.epoch + 1)) {
            left = left.min(recorded.saturating_sub(spent));
        }
        let breeding = &self.breeding;
        // One climb for the whole run: every island nudges the run's best, and the island that
        // holds it (the lowest index on a tie) judges the nudges.
        let local = &breeding.variation.local_search;
        let shared = (local.shared && local.fraction > 0.0).then(|| {
            let holder = (0..islands)
                .reduce(|best, i| {
                    let (a, b) = (self.islands[i].best(), self.islands[best].best());
                    if a.outcome.is_fitter_than(&b.outcome) {
                        i
                    } else {
                        best
                    }
                })
                .expect("a run has islands");
            let slot = self.islands[holder].best_index();
            let genome = self.islands[holder].population[slot].genome.clone();
            let site =
                (local.insertion > 0.0).then(|| BoundarySite::new(&genome, &breeding.scene, dims));
            (holder, SharedBest { genome, slot, site })
        });
        let mut children: Vec<Vec<Child>> = self
            .islands
            .iter_mut()
            .enumerate()
            .map(|(i, island)| {
                let share = left / islands as u64 + u64::from((i as u64) < left % islands as u64);
                let count = (self.children_per_island as u64).min(share) as usize;
                island.breed(count, breeding, dims, shared.as_ref().map(|(_, s)| s))
            })
            .collect();
        if let Some((holder, _)) = shared {
            let mut handed = Vec::new();
            for (i, island_children) in children.iter_mut().enumerate() {
                if i != holder {
                    let (nudges, crossovers) = std::mem::take(island_children)
                        .into_iter()
                        .partition(|c: &Child| c.nudge && !c.combined);
                    *island_children = crossovers;
                    handed.extend(nudges);
                }
            }
            children[holder].extend(handed);
        }
        children
    }

    /// Migration, when this epoch is one of its interval's.
    pub(super) fn migrate(&mut self, config: &RunConfig) -> Vec<MigrationRecord> {
        let migration = &config.raw.search.migration;
        let mut migrations = Vec::new();
        if migration.interval > 0 && self.epoch.is_multiple_of(migration.interval) {
            for event in migrate(&mut self.islands, migration, &mut self.migration_rng) {
                info!(epoch = self.epoch, from = %event.from, to = %event.to, emigrant = event.emigrant, replaced = ?event.replaced, task = %event.task, "migration");
                migrations.push(MigrationRecord {
                    from: event.from.0,
                    to: event.to.0,
                    emigrant_slot: event.emigrant,
                    replaced_slot: event.replaced,
                    task_id: event.task,
                });
            }
        }
        migrations
    }

    /// Moves to the next resolution once progress stalls there, re-evaluating every population
    /// (or, with `resolution.merge_islands`, the islands' best in turn as one population of
    /// `resolution.merged_population`). With less budget left than that re-evaluation, the run
    /// ends here (`switch_unaffordable`) rather than overshoot its budget or breed on at a level
    /// it would have left: a run resumed with a larger budget then switches where the run with
    /// that budget from the start did, and replays to the same bits.
    pub(super) fn switch_if_stalled(
        &mut self,
        config: &RunConfig,
        evaluator: &mut dyn Evaluator,
        ctx: &RunContext<'_>,
    ) -> Result<()> {
        let schedule = &config.raw.resolution;
        let merge = schedule.merge_islands && self.islands.len() > 1;
        let merged = schedule
            .merged_population
            .unwrap_or(config.raw.search.population);
        let individuals: usize = self.islands.iter().map(|i| i.population.len()).sum();
        let reevaluations = if merge {
            individuals.min(merged)
        } else {
            individuals
        } as u64;
        let watched = if schedule.stall_on_finest && !self.resolution.is_final(schedule) {
            self.check_on_finest(config, evaluator, ctx)?
        } else {
            self.best().outcome.rank()
        };
        let switch_affordable = config
            .raw
            .budget
            .evaluations
            .is_none_or(|max| max.saturating_sub(self.evaluations) >= reevaluations);
        let mut next = self.resolution.clone();
        let switch = next.observe(watched, self.evaluations, schedule);
        if switch && !switch_affordable {
            self.switch_unaffordable = true;
            return Ok(());
        }
        self.resolution = next;
        if !switch {
            return Ok(());
        }
        if let Some(overlap) = self.overlap.take() {
            self.drop_overlap(overlap);
        }
        self.finest_checked = None;
        // Its score is at the finest level: it can only join a population scored there.
        let checked_best = (self.checked_best.take())
            .filter(|_| schedule.carry_checked_best && self.resolution.is_final(schedule));
        let carried: Vec<Vec<(usize, usize)>> = if merge {
            vec![merge_order(&self.islands, merged)]
        } else {
            (self.islands.iter().enumerate())
                .map(|(i, island)| (0..island.population.len()).map(|s| (i, s)).collect())
                .collect()
        };
        let dims = schedule.dims(self.resolution.level);
        info!(epoch = self.epoch, resolution = %dims, merge, "re-evaluating at the next resolution (progress stalled, or resolution.latest_switch reached)");
        let genomes: Vec<Vec<Genome>> = carried
            .iter()
            .map(|group| {
                (group.iter())
                    .map(|&(i, s)| self.islands[i].population[s].genome.clone())
                    .collect()
            })
            .collect();
        let outcomes =
            evaluate_settled(self, evaluator, &genomes, dims, Purpose::Reevaluation, ctx)?;
        if merge {
            // The merged island draws from the stream after the islands' own (stream 0 is
            // migration's, 1..=islands the islands'), so the run stays a function of its seed.
            let mut rng = ChaCha8Rng::seed_from_u64(config.raw.seed);
            rng.set_stream(config.raw.search.islands as u64 + 1);
            let population = (genomes.into_iter().flatten())
                .zip(outcomes.into_iter().flatten())
                .map(|(genome, (task, outcome))| Individual {
                    genome,
                    outcome,
                    task,
                })
                .collect();
            self.children_per_island *= self.islands.len();
            self.islands = vec![Island::from_evaluated(IslandId(0), rng, population)];
        } else {
            for (island, outcomes) in self.islands.iter_mut().zip(outcomes) {
                for (ind, (task, outcome)) in island.population.iter_mut().zip(outcomes) {
                    ind.outcome = outcome;
                    ind.task = task;
                }
            }
        }
        if let Some((island, design)) = checked_best {
            // Merged islands are one: the design joins it wherever it was checked.
            let island = island.min(self.islands.len() - 1);
            if let Some(slot) = carry_checked(&mut self.islands[island], design) {
                info!(
                    epoch = self.epoch,
                    island, slot, "the best design checked at the finest level carried into it"
                );
            }
        }
        Ok(())
    }

    /// Islands on demand: splits the one population into the configured islands once the run's
    /// best at the finest resolution has stalled for `search.split_after_stall` epochs. The split
    /// islands draw from the streams after merging's (`islands + 2` onwards).
    pub(super) fn split_if_stalled(&mut self, config: &RunConfig) {
        let raw = &config.raw;
        if !self.resolution.is_final(&raw.resolution)
            || !(self.split).observe(self.best().outcome.rank(), raw.resolution.min_improvement)
        {
            return;
        }
        // Children bred ahead wait only beside a coarse level's finest check; the switch to the
        // finest level drops them, so none can be held from the islands before the split.
        debug_assert!(self.overlap.is_none(), "children held at the finest level");
        let whole = self.islands.pop().expect("an unsplit run has one island");
        let islands = raw.search.islands;
        info!(
            epoch = self.epoch,
            islands,
            "splitting the population into islands (progress stalled at the finest resolution)"
        );
        self.islands = split_island(whole, islands, raw.seed, islands as u64 + 2);
        self.children_per_island = raw.search.children_per_epoch;
    }

    pub(super) fn best(&self) -> &Individual {
        fittest(self.islands.iter().map(|i| i.best()))
    }

    /// Each island's line of `history.csv` for the epoch just applied.
    pub(super) fn history_rows(
        &self,
        scene: &Scene,
        dims: GridDims,
        replacements: &[usize],
    ) -> Vec<HistoryRow> {
        let wall = self.clock.seconds();
        self.islands
            .iter()
            .zip(replacements)
            .map(|(island, &replacements)| {
                history_row(
                    scene,
                    island,
                    self.epoch,
                    self.evaluations,
                    wall,
                    dims,
                    replacements,
                )
            })
            .collect()
    }
}

fn genomes_of(children: &[Vec<Child>]) -> Vec<Vec<Genome>> {
    children
        .iter()
        .map(|c| c.iter().map(|c| c.genome.clone()).collect())
        .collect()
}

/// Stores the end of an epoch. While replaying, first checks the replayed populations against the
/// ones the earlier session recorded: any difference means the store is not this run's.
pub(super) fn record_epoch(
    search: &Search,
    migrations: &[MigrationRecord],
    dims: GridDims,
    store: &RunStore,
) -> Result<()> {
    let populations: Vec<Vec<(TaskId, Option<f64>)>> = search
        .islands
        .iter()
        .map(|i| {
            i.population
                .iter()
                .map(|ind| (ind.task, ind.outcome.fitness()))
                .collect()
        })
        .collect();
    if search.replay_until.is_some_and(|last| search.epoch <= last) {
        let stored = store.population(search.epoch)?;
        let replayed: Vec<Vec<TaskId>> = populations
            .iter()
            .map(|p| p.iter().map(|&(t, _)| t).collect())
            .collect();
        if stored != replayed {
            return Err(RunError::Replay(format!(
                "the replayed populations of epoch {} differ from the ones {} recorded",
                search.epoch,
                store.path().display()
            )));
        }
    }
    store.record_epoch(&EpochRecord {
        epoch: search.epoch,
        evaluations: search.evaluations,
        wall_seconds: search.clock.seconds(),
        resolution: dims.to_string(),
        best_fitness: search.best().outcome.fitness(),
        populations,
        migrations,
    })?;
    Ok(())
}

fn history_row(
    scene: &Scene,
    island: &Island,
    epoch: usize,
    evaluations: u64,
    wall_seconds: f64,
    dims: GridDims,
    replacements: usize,
) -> HistoryRow {
    let best = island.best();
    let valid: Vec<f64> = island
        .population
        .iter()
        .filter_map(|i| i.outcome.fitness())
        .collect();
    HistoryRow {
        epoch,
        evaluations,
        wall_seconds,
        resolution: dims.to_string(),
        island: island.id.0,
        best_fitness: best.outcome.fitness(),
        best_figure: scene.figure(&best.outcome),
        mean_fitness: (!valid.is_empty()).then(|| valid.iter().sum::<f64>() / valid.len() as f64),
        replacements,
    }
}
