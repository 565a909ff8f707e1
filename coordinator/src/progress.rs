//! The terminal progress bar: evaluations, evaluations per second, the best design's headline
//! figure overall and per island, and the cluster's state (workers, leases). An embedding program
//! (the Python package) hears each epoch's history rows through an observer instead.

use std::sync::Arc;

use amorph::voxel::GridDims;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::summary::{HistoryRow, RunSummary};

#[derive(Debug, Clone)]
pub struct Progress {
    bar: ProgressBar,
    observer: Option<Observer>,
}

/// What an observer does with an epoch's history rows.
type EpochRows = dyn Fn(&[HistoryRow]) + Send + Sync;

/// Called with each island's history row at the end of every epoch, from the run's thread.
#[derive(Clone)]
struct Observer(Arc<EpochRows>);

impl std::fmt::Debug for Observer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Observer")
    }
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
        Self {
            bar,
            observer: None,
        }
    }

    /// Reports nothing (tests, embedded use).
    pub fn hidden() -> Self {
        Self {
            bar: ProgressBar::hidden(),
            observer: None,
        }
    }

    /// No bar; `observer` hears every epoch's history rows, one per island.
    pub fn observed(observer: impl Fn(&[HistoryRow]) + Send + Sync + 'static) -> Self {
        Self {
            bar: ProgressBar::hidden(),
            observer: Some(Observer(Arc::new(observer))),
        }
    }

    /// The epoch's history rows, for the observer if there is one.
    pub fn history(&self, rows: &[HistoryRow]) {
        if let Some(Observer(observer)) = &self.observer {
            observer(rows);
        }
    }

    pub fn evaluated(&self) {
        self.bar.inc(1);
    }

    /// `best` is the task's headline figure of the best design so far (RMS error, speed),
    /// `islands` each island's, `cluster` the evaluator's state if it has one.
    pub fn epoch(
        &self,
        epoch: usize,
        best: Option<String>,
        dims: GridDims,
        islands: &[Option<String>],
        cluster: Option<&str>,
    ) {
        let dash = || "-".to_owned();
        let mut line = format!("epoch {epoch}, {dims}, best {}", best.unwrap_or_else(dash));
        if islands.len() > 1 {
            let each: Vec<String> = islands
                .iter()
                .map(|b| b.clone().unwrap_or_else(dash))
                .collect();
            line.push_str(&format!(" | islands: {}", each.join(", ")));
        }
        if let Some(cluster) = cluster {
            line.push_str(&format!(" | {cluster}"));
        }
        self.bar.set_message(line);
    }

    pub fn finish(&self, summary: &RunSummary) {
        self.bar.finish_with_message(format!(
            "done ({:?}) after {} epochs",
            summary.stop, summary.epochs
        ));
    }
}
