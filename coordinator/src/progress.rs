//! The terminal progress bar: evaluations, evaluations per second and the best RMS error.

use amorph::voxel::GridDims;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::run::RunSummary;

#[derive(Debug, Clone)]
pub struct Progress {
    bar: ProgressBar,
}

impl Progress {
    /// A bar on stderr (drawn only when stderr is a terminal); `total` is the evaluation budget.
    pub fn stderr(total: Option<u64>) -> Self {
        let bar = match total {
            Some(n) => ProgressBar::with_draw_target(Some(n), ProgressDrawTarget::stderr()),
            None => ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr()),
        };
        bar.set_style(
            ProgressStyle::with_template(
                "{elapsed_precise} {bar:30.cyan/blue} {human_pos}/{human_len} evaluations ({per_sec}) {msg}",
            )
            .expect("static template is valid"),
        );
        Self { bar }
    }

    /// Reports nothing (tests, embedded use).
    pub fn hidden() -> Self {
        Self {
            bar: ProgressBar::hidden(),
        }
    }

    pub fn evaluated(&self) {
        self.bar.inc(1);
    }

    /// `best` is the task's headline figure of the best design so far (RMS error, speed).
    pub fn epoch(&self, epoch: usize, best: Option<String>, dims: GridDims) {
        let best = best.unwrap_or_else(|| "-".into());
        self.bar
            .set_message(format!("epoch {epoch}, {dims}, best {best}"));
    }

    pub fn finish(&self, summary: &RunSummary) {
        self.bar.finish_with_message(format!(
            "done ({:?}) after {} epochs",
            summary.stop, summary.epochs
        ));
    }
}
