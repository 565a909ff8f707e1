//! A saved design's files for a machine and for people: what `worker export` and the Python
//! package's `Scene.export` write.

use std::path::{Path, PathBuf};

use amorph::export::PrintPitch;
use amorph::genome::Genome;
use amorph::task::{Outcome, Scene};
use amorph::voxel::GridDims;

/// What to write besides the fabrication files every export has.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ExportOptions {
    /// Each material's region of the genome's continuous field meshed with about this many
    /// samples along the longest side (`material-<i>-<name>-smooth.stl`).
    pub smooth: Option<usize>,
    /// A voxel-print slice stack at this pitch (`slices/`).
    pub print: Option<PrintPitch>,
}

/// What an export wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct Exported {
    pub files: Vec<PathBuf>,
    pub voxels: usize,
    pub outcome: Outcome,
}

#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("the genome does not fit the scene: {0}")]
    Genome(#[from] amorph::genome::GenomeError),
    #[error("writing {what} into {dir}: {source}")]
    Write {
        what: &'static str,
        dir: String,
        source: std::io::Error,
    },
}

/// Writes the fabrication files of `genome` at `dims` into `out`: one STL per material (mm),
/// design.3mf, design.vxa, design.png, one SVG per laser-cut layer, the task's own pictures
/// (a beam's profile, a robot's walk) and for a robot voxcraft's VXA + VXD. The task's pictures
/// need the design's evaluation, which `evaluate` makes (on whatever threads the caller likes).
pub fn export_design(
    genome: &Genome,
    scene: &Scene,
    dims: GridDims,
    out: &Path,
    options: ExportOptions,
    evaluate: impl FnOnce() -> Outcome,
) -> Result<Exported, ExportError> {
    genome.validate(scene.limits(), scene.palette().len())?;
    let write_error = |what: &'static str| {
        move |source| ExportError::Write {
            what,
            dir: out.display().to_string(),
            source,
        }
    };
    let grid = scene.design(genome, dims);
    let outcome = evaluate();
    // The writers name their files relative to `out`.
    let mut files = amorph::export::write_fabrication_files(out, &grid, scene, Some(&outcome))
        .map_err(write_error("the fabrication files"))?;
    if let Some(samples) = options.smooth {
        files.extend(
            amorph::export::write_smooth_surfaces(out, genome, scene, dims, samples)
                .map_err(write_error("the smooth surfaces"))?,
        );
    }
    if let Some(pitch) = options.print {
        files.extend(
            amorph::export::write_slice_stack(out, genome, scene, dims, pitch)
                .map_err(write_error("the slice stack"))?,
        );
    }
    let artefacts = scene
        .write_artefacts(out, genome, dims, &outcome)
        .map_err(write_error("the task's pictures"))?;
    files.extend(artefacts.into_iter().map(|a| PathBuf::from(a.path)));
    let files = files.into_iter().map(|f| out.join(f)).collect();
    Ok(Exported {
        files,
        voxels: grid.filled_count(),
        outcome,
    })
}
