//! What a resumed run reads back from its own store: the evaluations to replay, the populations
//! and the epochs' counts.

use std::collections::HashMap;

use super::{Result, RunStore, StoreError, StoredEvaluation};
use crate::ids::TaskId;

impl RunStore {
    /// Every stored evaluation by task id, for a resumed run's replay.
    pub fn evaluations(&self) -> Result<HashMap<TaskId, StoredEvaluation>> {
        let rows: Vec<(i64, String, String, String, bool)> = self.with(|c| {
            let mut stmt = c.prepare(
                "SELECT task_id, genome, resolution, outcome, task_id IN (SELECT task_id FROM unchecked) FROM evaluation",
            )?;
            let rows = stmt
                .query_map([], |r| {
                    Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?, r.get(4)?))
                })?
                .collect::<rusqlite::Result<Vec<_>>>()?;
            Ok(rows)
        })?;
        rows.into_iter()
            .map(|(id, genome_json, resolution, outcome, unchecked)| {
                let id = u64::try_from(id).map_err(|_| StoreError::Corrupt {
                    path: self.path.clone(),
                    message: format!("table evaluation, row task_id {id}: negative task id"),
                })?;
                let outcome = serde_json::from_str(&outcome).map_err(|e| StoreError::Corrupt {
                    path: self.path.clone(),
                    message: format!("evaluation of task {id}: {e}"),
                })?;
                Ok((
                    TaskId(id),
                    StoredEvaluation {
                        genome_json,
                        resolution,
                        outcome,
                        unchecked,
                    },
                ))
            })
            .collect()
    }

    /// Wall seconds the run had used at its last recorded epoch (0 for a new run).
    pub fn recorded_wall_seconds(&self) -> Result<f64> {
        self.with(|c| {
            c.query_row(
                "SELECT COALESCE(MAX(wall_seconds), 0.0) FROM epoch",
                [],
                |r| r.get(0),
            )
        })
    }

    /// The run's evaluation count at the end of every recorded epoch, by epoch (empty before the
    /// first epoch ended; the last recorded epoch is its largest key).
    pub fn epoch_evaluations(&self) -> Result<HashMap<usize, u64>> {
        let rows: Vec<(i64, i64)> = self.with(|c| {
            let mut stmt = c.prepare("SELECT epoch, evaluations FROM epoch")?;
            let rows = stmt
                .query_map([], |r| Ok((r.get(0)?, r.get(1)?)))?
                .collect::<rusqlite::Result<Vec<_>>>()?;
            Ok(rows)
        })?;
        rows.into_iter()
            .map(
                |(epoch, n)| match (usize::try_from(epoch), u64::try_from(n)) {
                    (Ok(epoch), Ok(n)) => Ok((epoch, n)),
                    _ => Err(StoreError::Corrupt {
                        path: self.path.clone(),
                        message: format!("table epoch, row epoch {epoch}: evaluations {n}"),
                    }),
                },
            )
            .collect()
    }

    /// The population of every island after `epoch`, as task ids in slot order.
    pub fn population(&self, epoch: usize) -> Result<Vec<Vec<TaskId>>> {
        let rows: Vec<(i64, i64, i64)> = self.with(|c| {
            let mut stmt = c.prepare(
                "SELECT island, slot, task_id FROM population WHERE epoch = ?1 ORDER BY island, slot",
            )?;
            let rows = stmt
                .query_map([epoch as i64], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))?
                .collect::<rusqlite::Result<Vec<_>>>()?;
            Ok(rows)
        })?;
        let mut islands: Vec<Vec<TaskId>> = Vec::new();
        for (island, slot, task) in rows {
            // A store is a file anyone may have edited: a row that cannot be a population entry
            // is an error naming it, never an index out of range or a huge allocation.
            let corrupt = |what: &str| StoreError::Corrupt {
                path: self.path.clone(),
                message: format!(
                    "table population, row (epoch {epoch}, island {island}, slot {slot}, task_id {task}): {what}"
                ),
            };
            let i = usize::try_from(island)
                .ok()
                .filter(|&i| i <= islands.len())
                .ok_or_else(|| corrupt("island out of order or out of range"))?;
            let task = u64::try_from(task).map_err(|_| corrupt("negative task id"))?;
            if i == islands.len() {
                islands.push(Vec::new());
            }
            islands[i].push(TaskId(task));
        }
        Ok(islands)
    }

    /// Number of evaluations stored.
    pub fn evaluation_count(&self) -> Result<u64> {
        self.with(|c| {
            c.query_row("SELECT COUNT(*) FROM evaluation", [], |r| {
                r.get::<_, i64>(0)
            })
        })
        .map(|n| n as u64)
    }
}
