//! A design named by its evaluation in a run folder (`worker export --run results/x --design ID`):
//! its genome and resolution from the run store, its scene from the run's config.toml. This is how
//! any member of a run's Pareto front (`pareto.csv`'s `task_id`) is exported.

use std::path::Path;

use amorph::genome::Genome;
use amorph::task::Scene;
use amorph::voxel::GridDims;
use rusqlite::{Connection, OpenFlags, OptionalExtension};

use crate::{Result, WorkerError, parse_genome, parse_resolution, read_scene};

/// The genome, scene and resolution of evaluation `task_id` of the run in `run_dir`. The store is
/// opened read-only, so a run still going is left alone.
pub fn read_run_design(run_dir: &Path, task_id: u64) -> Result<(Genome, Scene, GridDims)> {
    let store = run_dir.join("run.sqlite");
    let source = store.display().to_string();
    let fail = |message: String| WorkerError::Parse {
        path: source.clone(),
        message,
    };
    if !store.is_file() {
        return Err(fail(
            "no run store here (a run folder holds run.sqlite)".into(),
        ));
    }
    let id = i64::try_from(task_id).map_err(|_| fail(format!("design {task_id} is too large")))?;
    let row: Option<(String, String)> =
        Connection::open_with_flags(&store, OpenFlags::SQLITE_OPEN_READ_ONLY)
            .and_then(|c| {
                c.query_row(
                    "SELECT genome, resolution FROM evaluation WHERE task_id = ?1",
                    [id],
                    |r| Ok((r.get(0)?, r.get(1)?)),
                )
                .optional()
            })
            .map_err(|e| fail(e.to_string()))?;
    let (genome, resolution) =
        row.ok_or_else(|| fail(format!("no evaluation has task_id {task_id}")))?;
    let genome = parse_genome(&genome, &format!("{source}, evaluation {task_id}"))?;
    let dims = parse_resolution(&resolution)?;
    let scene = read_scene(&run_dir.join("config.toml"))?;
    Ok((genome, scene, dims))
}
