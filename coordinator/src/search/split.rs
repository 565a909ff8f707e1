//! Islands on demand (`search.split_after_stall`): a run breeds one population of
//! `islands × population` individuals, `islands × children_per_epoch` children an epoch, while its
//! best improves at the finest resolution, and splits it into `islands` islands only once that
//! best stalls: one population's climb until it stops, and only then the batch spent on separate
//! lineages. Measured in docs/evolution.md, session 26: it split on 2 runs of 17, helped one
//! (the discontinuous slope's stuck seed) and slowed the other, because the dealt islands hold
//! designs bred together rather than new lineages; off by default and recommended nowhere.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::island::Island;
use super::stall::Stall;
use crate::ids::IslandId;

/// Watches the run's best at the finest level and says when to split; a pure function of the
/// best-fitness sequence, so a replayed run splits at the same epoch.
#[derive(Clone, Debug)]
pub struct SplitWatch {
    after: usize,
    stall: Stall,
    done: bool,
}

impl SplitWatch {
    /// `after` epochs of stall at the finest level split the run; 0 never does (islands from the
    /// start, the paper's model).
    pub fn new(after: usize) -> Self {
        Self {
            after,
            stall: Stall::new(),
            done: after == 0,
        }
    }

    /// Records the run's best after an epoch at the finest level; true once, at the epoch the
    /// stall reaches `after` epochs.
    pub fn observe(&mut self, best: f64, min_improvement: f64) -> bool {
        if self.done {
            return false;
        }
        self.done = self.stall.observe(best, min_improvement) >= self.after;
        self.done
    }
}

/// Deals one island's population into `islands` islands by rank: island j takes the j-th fittest,
/// then the (j + islands)-th, and so on, so every island starts from one of the best few designs
/// and none holds only the tail. Island j draws from stream `first_stream + j` of the run seed.
/// Individuals keep their genomes, outcomes and task ids; each island's step and climb state start
/// afresh.
pub fn split_island(whole: Island, islands: usize, seed: u64, first_stream: u64) -> Vec<Island> {
    let order = whole.ranked_slots();
    let mut slots: Vec<Option<_>> = whole.population.into_iter().map(Some).collect();
    (0..islands)
        .map(|j| {
            let population = (order.iter().skip(j).step_by(islands))
                .map(|&s| slots[s].take().expect("each slot is dealt once"))
                .collect();
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(first_stream + j as u64);
            Island::from_evaluated(IslandId(j as u32), rng, population)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::fixtures::{failed, island};
    use rand::RngExt;

    #[test]
    fn a_watch_splits_once_after_its_stall() {
        let mut w = SplitWatch::new(2);
        assert!(!w.observe(-10.0, 0.02));
        assert!(!w.observe(-5.0, 0.02)); // progress
        assert!(!w.observe(-4.99, 0.02)); // stall 1
        assert!(w.observe(-4.99, 0.02)); // stall 2: split
        assert!(!w.observe(-4.99, 0.02), "a run splits once");
        let mut never = SplitWatch::new(0);
        assert!((0..20).all(|_| !never.observe(-1.0, 0.02)));
    }

    /// Seven individuals into three islands: ranks 0, 3, 6 / 1, 4 / 2, 5, ties in slot order,
    /// a failed design last; every individual lands exactly once, with its task id.
    #[test]
    fn the_population_is_dealt_by_rank() {
        let mut whole = island(
            0,
            &[0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6],
            &[-5.0, -1.0, -3.0, -1.0, -7.0, -2.0, -4.0],
        );
        whole.population[4].outcome = failed();
        // Ranks: slot 1, 3 (tie, slot order), 5, 2, 6, 0, 4 (failed).
        let split = split_island(whole, 3, 9, 4);
        let tasks: Vec<Vec<u64>> = (split.iter())
            .map(|i| i.population.iter().map(|ind| ind.task.0).collect())
            .collect();
        assert_eq!(tasks, [vec![1, 2, 4], vec![3, 6], vec![5, 0]]);
        let ids: Vec<u32> = split.iter().map(|i| i.id.0).collect();
        assert_eq!(ids, [0, 1, 2]);
    }

    /// Island j's random numbers are stream `first_stream + j` of the seed, whatever the whole
    /// island drew before: the split is a function of the seed and the population alone.
    #[test]
    fn split_islands_draw_from_their_own_streams() {
        let whole = island(0, &[0.0, 0.1, 0.2, 0.3], &[-1.0, -2.0, -3.0, -4.0]);
        let mut split = split_island(whole, 2, 9, 4);
        for (j, island) in split.iter_mut().enumerate() {
            let mut expected = ChaCha8Rng::seed_from_u64(9);
            expected.set_stream(4 + j as u64);
            assert_eq!(island.rng_mut().random::<u64>(), expected.random::<u64>());
        }
    }
}
