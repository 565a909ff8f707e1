//! Which of an epoch's nudges an island adds up for the next epoch (`local_search.combine`):
//! the improving ones (`search::combination`), the residual model's pick
//! (`search::residual_model`), or its least-squares step (`search::least_squares`). All
//! read the epoch's children and outcomes only, so a replayed epoch offers the same designs.

use amorph::genome::Genome;
use amorph::task::Outcome;
use tracing::info;

use super::{Child, Island};
use crate::search::combination::{CombineBy, Combining, combinations};
use crate::search::least_squares;
use crate::search::residual_model::{self, Measured, Nudged};

impl Island {
    /// The designs this epoch's nudges offer the next epoch, as `combining.by` picks them.
    pub(super) fn combine_nudges(
        &self,
        children: &[Child],
        outcomes: &[&Outcome],
        wins: &[bool],
        combining: &Combining,
    ) -> Vec<Genome> {
        if combining.by == CombineBy::Fitness {
            return self.combine_improving_nudges(children, outcomes, wins, combining);
        }
        // Both residual rules read the epoch the same way; nothing without residuals.
        let Some(epoch) = self.measured_nudges(children, outcomes, wins, combining) else {
            return Vec::new();
        };
        match combining.by {
            CombineBy::LeastSquares => self.combine_by_least_squares(&epoch, combining),
            _ => self.combine_by_residuals(&epoch, combining),
        }
    }

    /// The nudges of this epoch that beat the design they started from (the snapshot occupant of
    /// their dominant parent's slot, before any child of the epoch is applied), fittest first
    /// (child order on a tie), added up by [`combinations`]. The slot's occupant after the epoch,
    /// what `rebase` builds on, is the last child `wins` gives it, or the one it had.
    fn combine_improving_nudges(
        &self,
        children: &[Child],
        outcomes: &[&Outcome],
        wins: &[bool],
        combining: &Combining,
    ) -> Vec<Genome> {
        let mut improving: Vec<(usize, &Child)> = children
            .iter()
            .enumerate()
            .filter(|(k, c)| {
                c.nudge
                    && !c.combined
                    && outcomes[*k].is_fitter_than(&self.population[c.dominant_parent].outcome)
            })
            .collect();
        // Nudges of one epoch share one base (the island's best, or the run's under `shared`).
        let Some(slot) = improving.first().map(|(_, c)| c.dominant_parent) else {
            return Vec::new();
        };
        improving.retain(|(_, c)| c.dominant_parent == slot);
        let base = &self.population[slot].genome;
        let onto = last_winner(children, wins, slot).map_or(base, |k| &children[k].genome);
        // A stable sort, so ties keep child order.
        improving.sort_by(|(a, _), (b, _)| outcomes[*b].rank().total_cmp(&outcomes[*a].rank()));
        let genomes: Vec<&Genome> = improving.iter().map(|(_, c)| &c.genome).collect();
        let offered = combinations(base, onto, &genomes, combining);
        if !offered.is_empty() {
            info!(island = %self.id, improving = genomes.len(), offered = offered.len(), "improving nudges combined");
        }
        offered
    }

    /// The nudges of this epoch (improving or not, their residuals lined up with their base's)
    /// that the residual model picks ([`residual_model::select`]), added up in the order it
    /// picked them by [`combinations`].
    fn combine_by_residuals(&self, epoch: &MeasuredNudges, combining: &Combining) -> Vec<Genome> {
        let (base, onto) = (epoch.base(), epoch.onto());
        let chosen =
            residual_model::select(&base, &onto, &epoch.nudges, combining.limits.max_points);
        let genomes: Vec<&Genome> = chosen.iter().map(|&k| epoch.nudges[k].genome).collect();
        let offered = combinations(base.genome, onto.genome, &genomes, combining);
        if !offered.is_empty() {
            info!(island = %self.id, nudges = epoch.nudges.len(), chosen = genomes.len(), offered = offered.len(), "nudges combined by their residuals");
        }
        offered
    }

    /// The residual model's least-squares step along this epoch's nudges
    /// ([`least_squares::step`]), whole, then a half, a quarter, ... of its moves, up to
    /// `combinations` distinct designs. Nothing when no step lowers the predicted error.
    fn combine_by_least_squares(
        &self,
        epoch: &MeasuredNudges,
        combining: &Combining,
    ) -> Vec<Genome> {
        let (base, onto) = (epoch.base(), epoch.onto());
        let limits = &combining.limits;
        let Some(step) = least_squares::step(
            &base,
            &onto,
            &epoch.nudges,
            combining.reach,
            limits.max_points,
        ) else {
            return Vec::new();
        };
        let mut offered: Vec<Genome> = Vec::new();
        let mut scale = 1.0;
        for _ in 0..combining.combinations {
            if let Some(design) = least_squares::apply(
                base.genome,
                onto.genome,
                &epoch.nudges,
                &step,
                scale,
                limits,
            ) && !offered.contains(&design)
            {
                offered.push(design);
            }
            scale /= 2.0;
        }
        info!(island = %self.id, nudges = epoch.nudges.len(), predicted = step.predicted, offered = offered.len(), "nudges combined by a least-squares step");
        offered
    }

    /// This epoch's nudges of one slot with their residuals lined up with the base's, and what
    /// the model builds on: the base, or (rebased) the slot's occupant after the epoch, whose own
    /// residuals are measured (the winning nudge, or last epoch's combination). `None` when the
    /// base or that occupant carries no residuals.
    fn measured_nudges<'a>(
        &'a self,
        children: &'a [Child],
        outcomes: &[&'a Outcome],
        wins: &[bool],
        combining: &Combining,
    ) -> Option<MeasuredNudges<'a>> {
        let slot = (children.iter())
            .find(|c| c.nudge && !c.combined)
            .map(|c| c.dominant_parent)?;
        let base = &self.population[slot];
        let base_residuals = base.outcome.metrics().and_then(|m| m.residuals())?;
        let nudges: Vec<Nudged> = (children.iter().zip(outcomes))
            .filter(|(c, _)| c.nudge && !c.combined && c.dominant_parent == slot)
            .filter_map(|(c, o)| {
                let residuals = o.metrics()?.residuals()?;
                Some(Nudged {
                    genome: &c.genome,
                    residuals: residual_model::aligned(&base_residuals, &residuals)?,
                })
            })
            .collect();
        let onto = match last_winner(children, wins, slot) {
            Some(k) if combining.rebase => {
                let residuals = (outcomes[k].metrics())
                    .and_then(|m| m.residuals())
                    .and_then(|r| residual_model::aligned(&base_residuals, &r))?;
                Some((&children[k].genome, residuals))
            }
            _ => None,
        };
        Some(MeasuredNudges {
            base: &base.genome,
            base_residuals: base_residuals.iter().map(|r| r[1]).collect(),
            onto,
            nudges,
        })
    }
}

/// An epoch's nudges as the residual model reads them ([`Island::measured_nudges`]).
struct MeasuredNudges<'a> {
    base: &'a Genome,
    base_residuals: Vec<f64>,
    /// The rebased design and its residuals; `None`: the base itself.
    onto: Option<(&'a Genome, Vec<f64>)>,
    nudges: Vec<Nudged<'a>>,
}

impl MeasuredNudges<'_> {
    fn base(&self) -> Measured<'_> {
        Measured {
            genome: self.base,
            residuals: &self.base_residuals,
        }
    }

    fn onto(&self) -> Measured<'_> {
        match &self.onto {
            Some((genome, residuals)) => Measured { genome, residuals },
            None => self.base(),
        }
    }
}

/// The child that holds `slot` after the epoch (the last one `wins` gives it), if any: what
/// `rebase` builds on.
fn last_winner(children: &[Child], wins: &[bool], slot: usize) -> Option<usize> {
    (children.iter().zip(wins)).rposition(|(c, won)| *won && c.dominant_parent == slot)
}
