//! The state of a search between epochs and the four things that change it: the initial
//! populations, an epoch (breed, evaluate, settle, apply), migration, and the switch to the next
//! resolution (`switch`, with the coarse level's checks at the finest one in `finest`). Each is a
//! function of the seed and the outcomes alone, so a replay from the run store retraces it
//! exactly (`record`).

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

use amorph::genome::Genome;
use amorph::task::{Outcome, Scene};
use amorph::voxel::GridDims;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tracing::info;

use super::batch::{Ledger, evaluate_all, evaluate_settled, settle};
use super::{Result, RunContext};
use crate::config::RunConfig;
use crate::evaluator::Evaluator;
use crate::ids::IslandId;
use crate::search::{
    Breeding, Child, Individual, Island, ParentDesigns, Pareto, ResolutionState, SharedBest,
    first_in_turn, keep_at_least_one, migrate,
};
use crate::store::{MigrationRecord, Purpose};
use crate::summary::fittest;
use crate::verification::Evaluated;

mod finest;
mod record;
mod switch;

use finest::Overlap;
pub(super) use record::record_epoch;

pub(super) struct Search {
    pub(super) islands: Vec<Island>,
    migration_rng: ChaCha8Rng,
    pub(super) resolution: ResolutionState,
    /// The epochs, evaluations and task numbers so far, and what an earlier session stored.
    pub(super) ledger: Ledger,
    /// The last epoch that session recorded: up to it the replay must match the store exactly.
    pub(super) replay_until: Option<usize>,
    /// The evaluation count at the end of every epoch an earlier session recorded: where a
    /// session's budget ended the run inside an epoch, it bred that epoch short, and so must its
    /// replay (see `breed_children`).
    replay_epoch_evaluations: HashMap<usize, u64>,
    pub(super) clock: RunClock,
    breeding: Breeding,
    /// With `resolution.stall_on_finest`: the last best genome evaluated at the finest level at
    /// this coarse level.
    finest_checked: Option<Genome>,
    /// The best rank those checks have given at this level: what the stall rule watches.
    checked_best: f64,
    /// The level stalled with less budget left than the switch's re-evaluation: the run ends.
    pub(super) switch_unaffordable: bool,
    /// The next epoch's children, sent out beside a finest-level check and waiting for the stall
    /// rule's verdict.
    overlap: Option<Overlap>,
    /// With `search.skip_unchanged`: the parents' designs at this level, to tell the children
    /// that make them.
    parent_designs: Option<ParentDesigns>,
    /// Children not evaluated because they made their dominant parent's design.
    pub(super) unchanged_children: u64,
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
        let breeding = Breeding {
            mutation: config.search.mutation.clone(),
            local_search: config.search.local_search.clone(),
            scene,
        };
        let island_rng = |i: usize| {
            let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
            rng.set_stream(i as u64 + 1);
            rng
        };
        let mut migration_rng = ChaCha8Rng::seed_from_u64(config.seed);
        migration_rng.set_stream(0);

        let mut rngs: Vec<ChaCha8Rng> = (0..config.search.islands).map(island_rng).collect();
        let initial: Vec<Vec<Genome>> = rngs
            .iter_mut()
            .map(|rng| {
                Island::initial_genomes(
                    rng,
                    config.search.population,
                    config.search.initial_points,
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
            ledger: Ledger {
                epoch: 0,
                evaluations: 0,
                next_task: 0,
                replay,
            },
            replay_until,
            replay_epoch_evaluations,
            clock: RunClock {
                started: Instant::now(),
                earlier: ctx.store.recorded_wall_seconds()?,
            },
            breeding,
            finest_checked: None,
            checked_best: f64::NEG_INFINITY,
            switch_unaffordable: false,
            overlap: None,
            parent_designs: config.search.skip_unchanged.then(ParentDesigns::default),
            unchanged_children: 0,
        };
        search.breed_for_level(config);
        let dims = config.resolution.dims(0);
        let objectives = &config.search.objectives;
        let pareto = (!objectives.is_empty()).then(|| {
            Pareto::new(
                search.breeding.scene.clone(),
                objectives,
                config.search.selection,
                &config.search.hypervolume_reference,
                dims,
            )
        });
        let outcomes = evaluate_settled(
            &mut search.ledger,
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
                    .with_pareto(pareto.clone())
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
        let local = &self.breeding.local_search;
        let combine = local
            .combine
            .then_some(self.breeding.scene.limits().max_points);
        let (children, genomes, batch) = match self.overlap.take() {
            Some(overlap) if overlap.dims == dims => {
                overlap.held.keep(&mut self.ledger, ctx)?;
                (overlap.children, overlap.genomes, overlap.batch)
            }
            other => {
                if let Some(overlap) = other {
                    self.drop_overlap(overlap);
                }
                let children = self.breed_children(config, dims, self.ledger.evaluations);
                let genomes = genomes_of(&children);
                let batch = evaluate_all(
                    &mut self.ledger,
                    evaluator,
                    &genomes,
                    dims,
                    Purpose::Child,
                    ctx,
                )?;
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
        self.ledger.epoch += 1;
        Ok(self
            .islands
            .iter_mut()
            .zip(children)
            .zip(outcomes)
            .map(|((island, children), outcomes)| island.apply(children, outcomes, combine))
            .collect())
    }

    /// Sets the local search to act as configured at the current level
    /// (`local_search.finest_fraction` at the finest).
    pub(super) fn breed_for_level(&mut self, config: &RunConfig) {
        let finest = self.resolution.is_final(&config.resolution);
        self.breeding.local_search = (config.search.local_search).at_level(finest);
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
        let islands = self.islands.len();
        let mut left = config
            .budget
            .evaluations
            .map_or(u64::MAX, |max| max.saturating_sub(spent));
        // A recorded epoch is bred as the session that recorded it bred it: if that session's
        // budget cut the epoch short (the run ended there and was resumed with a larger budget),
        // its recorded evaluations say how short; otherwise they leave room for every child and
        // change nothing.
        if let Some(&recorded) = self.replay_epoch_evaluations.get(&(self.ledger.epoch + 1)) {
            left = left.min(recorded.saturating_sub(spent));
        }
        let breeding = &self.breeding;
        // One climb for the whole run: every island nudges the run's best, and the island that
        // holds it (the lowest index on a tie) judges the nudges.
        let local = &breeding.local_search;
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
            let site = local.boundary_site(&genome, &breeding.scene, dims);
            (holder, SharedBest { genome, slot, site })
        });
        // Skipping unchanged children, every island breeds its whole share and the budget cuts
        // the children left after the skip (`drop_unchanged`): what an epoch breeds then never
        // depends on the budget, so a replay needs only the count the store recorded.
        let skipping = self.parent_designs.is_some();
        let counts: Vec<usize> = (0..islands)
            .map(|i| {
                let share = left / islands as u64 + u64::from((i as u64) < left % islands as u64);
                let per_island = config.search.children_per_epoch;
                if skipping {
                    per_island
                } else {
                    (per_island as u64).min(share) as usize
                }
            })
            .collect();
        let mut children: Vec<Vec<Child>> = (self.islands.iter_mut().zip(&counts))
            .map(|(island, &count)| {
                let best = shared.as_ref().map(|(_, s)| s);
                island.breed(count, breeding, dims, best)
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
        if skipping {
            self.drop_unchanged(&mut children, dims, left);
        }
        children
    }

    /// Drops the children whose design is their dominant parent's (`search.skip_unchanged`), then
    /// all but the first `left` of the rest in turn.
    fn drop_unchanged(&mut self, children: &mut [Vec<Child>], dims: GridDims, left: u64) {
        let designs = self.parent_designs.as_mut().expect("skipping unchanged");
        let unchanged = designs.unchanged(&self.islands, children, &self.breeding.scene, dims);
        let mut keep: Vec<Vec<bool>> = (unchanged.iter())
            .map(|island| island.iter().map(|&u| !u).collect())
            .collect();
        keep_at_least_one(&mut keep);
        let dropped: u64 = (keep.iter().zip(&unchanged))
            .map(|(keep, unchanged)| {
                let dropped = keep.iter().zip(unchanged).filter(|(k, u)| **u && !**k);
                dropped.count() as u64
            })
            .sum();
        self.unchanged_children += dropped;
        if dropped > 0 {
            info!(
                epoch = self.ledger.epoch + 1,
                dropped, "children that make their dominant parent's design not evaluated"
            );
        }
        first_in_turn(&mut keep, left);
        for (children, keep) in children.iter_mut().zip(keep) {
            let mut keep = keep.into_iter();
            children.retain(|_| keep.next().expect("one flag per child"));
        }
    }

    /// Migration, when this epoch is one of its interval's.
    pub(super) fn migrate(&mut self, config: &RunConfig) -> Vec<MigrationRecord> {
        let migration = &config.search.migration;
        let mut migrations = Vec::new();
        if migration.interval > 0 && self.ledger.epoch.is_multiple_of(migration.interval) {
            for event in migrate(&mut self.islands, migration, &mut self.migration_rng) {
                info!(epoch = self.ledger.epoch, from = %event.from, to = %event.to, emigrant = event.emigrant, replaced = ?event.replaced, task = %event.task, "migration");
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

    pub(super) fn best(&self) -> &Individual {
        fittest(self.islands.iter().map(|i| i.best()))
    }

    /// What the stall rule watches, larger being better: the best fitness, or in a
    /// multi-objective run the hypervolume of all islands' populations together.
    pub(super) fn progress(&self) -> f64 {
        match self.islands[0].pareto() {
            Some(pareto) => {
                let outcomes: Vec<&Outcome> = (self.islands.iter())
                    .flat_map(|i| i.population.iter().map(|m| &m.outcome))
                    .collect();
                pareto.hypervolume(&outcomes)
            }
            None => self.best().outcome.rank(),
        }
    }
}

fn genomes_of(children: &[Vec<Child>]) -> Vec<Vec<Genome>> {
    children
        .iter()
        .map(|c| c.iter().map(|c| c.genome.clone()).collect())
        .collect()
}
