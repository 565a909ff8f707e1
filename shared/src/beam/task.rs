//! The beam task (paper §III): clamp the −Y layer, load the free-end layer downward, and score how
//! closely the deflected top surface follows a target profile.

use serde::{Deserialize, Serialize};

use super::target::TargetProfile;
use crate::genome::{Genome, GenomeLimits};
use crate::material::Palette;
use crate::outcome::{Failure, Metrics, Outcome};
use crate::statics::{self, StaticLoadCase, StaticModel, StaticSolverParams};
use crate::voxel::{DEFAULT_THRESHOLD, GridDims, VoxelGrid, keep_connected_to_base, voxelize};

/// Everything a beam evaluation needs besides the genome and the resolution.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamScene {
    /// The profile the deflected top surface should follow.
    pub target: TargetProfile,
    /// The materials genome indices refer to (default: hard and soft resin, 1000:1).
    #[serde(default = "Palette::hard_soft_resins")]
    pub palette: Palette,
    /// Edge length of the whole beam along Y in metres; the voxel size is this over the resolution's
    /// `ny`, so the same physical beam is simulated at every resolution.
    #[serde(default = "default_length")]
    pub length: f64,
    /// Total downward force on the free-end layer, N. The fitness is normalized by the tip
    /// deflection, so this only matters for the reported deflection in metres.
    #[serde(default = "default_tip_load")]
    pub tip_load: f64,
    /// Total-density threshold of the voxelization.
    #[serde(default = "default_threshold")]
    pub threshold: f64,
    /// Ranges and size limit a genome must respect.
    #[serde(default)]
    pub limits: GenomeLimits,
    /// Static solver settings.
    #[serde(default)]
    pub solver: StaticSolverParams,
}

fn default_length() -> f64 {
    0.04
}
fn default_tip_load() -> f64 {
    0.01
}
fn default_threshold() -> f64 {
    DEFAULT_THRESHOLD
}

impl BeamScene {
    pub fn new(target: TargetProfile) -> Self {
        Self {
            target,
            palette: Palette::hard_soft_resins(),
            length: default_length(),
            tip_load: default_tip_load(),
            threshold: default_threshold(),
            limits: GenomeLimits::default(),
            solver: StaticSolverParams::default(),
        }
    }

    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), String> {
        self.palette
            .validate()
            .map_err(|e| format!("palette: {e}"))?;
        self.limits.validate().map_err(|e| e.to_string())?;
        if !(self.length.is_finite() && self.length > 0.0) {
            return Err(format!("length = {} must be positive", self.length));
        }
        if !(self.tip_load.is_finite() && self.tip_load > 0.0) {
            return Err(format!("tip_load = {} must be positive", self.tip_load));
        }
        self.solver.validate().map_err(|e| format!("solver: {e}"))?;
        if !self.threshold.is_finite() {
            return Err(format!("threshold = {} must be finite", self.threshold));
        }
        Ok(())
    }
}

/// What a beam evaluation measured, for reports and plots.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BeamMetrics {
    /// RMS deviation of the normalized top surface from the target, percent of tip deflection
    /// (the paper's Table III measure).
    pub rms_percent: f64,
    /// Mean downward deflection of the tip layer's top surface, metres.
    pub tip_deflection: f64,
    /// Filled voxels connected to the clamp.
    pub voxels: usize,
    /// Of those, how many of each material.
    pub material_counts: Vec<usize>,
    /// Top-surface voxels (the highest of each column), averaged per station into the profile.
    pub surface_voxels: usize,
    /// Per station along the beam: normalized position, mean normalized deflection, target.
    pub profile: Vec<[f64; 3]>,
    /// Iterations the static solver took (0 for a direct solve).
    pub solver_iterations: usize,
    /// True relative residual of the solve.
    pub solver_residual: f64,
}

/// Voxelizes a genome into the part of the design a beam can use: voxels face-connected to the
/// clamped `y = 0` layer.
pub fn beam_design(genome: &Genome, scene: &BeamScene, dims: GridDims) -> VoxelGrid {
    let grid = voxelize(genome, dims, scene.palette.len(), scene.threshold);
    keep_connected_to_base(&grid)
}

/// Evaluates a genome as a beam at resolution `dims`. Every way a design can fail is an outcome.
pub fn evaluate_beam(genome: &Genome, scene: &BeamScene, dims: GridDims) -> Outcome {
    if let Err(e) = genome.validate(&scene.limits, scene.palette.len()) {
        return Outcome::failed(Failure::InvalidGenome(e.to_string()));
    }
    if dims.ny < 2 {
        return Outcome::failed(Failure::InvalidRequest(format!(
            "a beam needs at least 2 layers along y, got {dims}"
        )));
    }
    let grid = beam_design(genome, scene, dims);
    evaluate_beam_design(&grid, scene)
}

/// Evaluates an already voxelized design (only its voxels connected to the base count).
pub fn evaluate_beam_design(grid: &VoxelGrid, scene: &BeamScene) -> Outcome {
    let dims = grid.dims();
    let tip_y = dims.ny - 1;
    let layer = |y: usize| {
        (0..dims.nz)
            .flat_map(move |z| (0..dims.nx).map(move |x| (x, z)))
            .filter(move |&(x, z)| grid.get(x, y, z).is_some())
            .map(move |(x, z)| dims.index(x, y, z))
    };
    if grid.filled_count() == 0 {
        return Outcome::failed(Failure::Empty);
    }
    let tip_cells: Vec<usize> = layer(tip_y).collect();
    if tip_cells.is_empty() {
        return Outcome::failed(Failure::NotSpanning);
    }

    let voxel_size = scene.length / dims.ny as f64;
    let model = match StaticModel::new(grid, &scene.palette, voxel_size) {
        Ok(m) => m,
        Err(e) => return Outcome::failed(Failure::Solver(e.to_string())),
    };
    let node = |cell: usize| model.node_of_cell(cell).expect("filled cell has a node");
    let force = -scene.tip_load / tip_cells.len() as f64;
    let case = StaticLoadCase {
        fixed_nodes: layer(0).map(node).collect(),
        loads: tip_cells
            .iter()
            .map(|&c| (node(c), [0.0, 0.0, force, 0.0, 0.0, 0.0]))
            .collect(),
    };
    let solution = match statics::solve(&model, &case, &scene.solver) {
        Ok(s) => s,
        Err(e) => return Outcome::failed(Failure::Solver(e.to_string())),
    };

    // The top surface: the highest voxel of every (x, y) column; its downward deflection is −u_z
    // (a small rotation moves the top face sideways, not vertically).
    let surface: Vec<(usize, f64)> = (1..dims.ny)
        .flat_map(|y| (0..dims.nx).map(move |x| (x, y)))
        .filter_map(|(x, y)| {
            let z = (0..dims.nz).rev().find(|&z| grid.get(x, y, z).is_some())?;
            let u = solution.displacements[node(dims.index(x, y, z))];
            Some((y, -u[2]))
        })
        .collect();
    let tip: Vec<f64> = surface
        .iter()
        .filter(|&&(y, _)| y == tip_y)
        .map(|&(_, w)| w)
        .collect();
    let tip_deflection = tip.iter().sum::<f64>() / tip.len() as f64;
    if !(tip_deflection.is_finite() && tip_deflection > 0.0) {
        return Outcome::failed(Failure::Degenerate(format!(
            "tip deflection {tip_deflection:e} m is not downward"
        )));
    }

    // The profile along the beam: at every station (layer y ≥ 1) the mean deflection of the
    // top-surface voxels, normalized by the tip's. Comparing station means, not every column,
    // keeps the fitness independent of the design's width (a column count would reward narrow
    // beams) and makes fitness and RMS error two monotone views of one number.
    let station = |y: usize| y as f64 / tip_y as f64;
    let mut per_station = vec![(0.0, 0usize); dims.ny];
    for &(y, w) in &surface {
        per_station[y].0 += w / tip_deflection;
        per_station[y].1 += 1;
    }
    let profile: Vec<[f64; 3]> = std::iter::once([0.0, 0.0, 0.0])
        .chain(
            per_station
                .iter()
                .enumerate()
                .filter(|(_, (_, n))| *n > 0)
                .map(|(y, &(w, n))| {
                    let t = station(y);
                    [t, w / n as f64, scene.target.deflection(t)]
                }),
        )
        .collect();
    let stations = &profile[1..];
    let sum_sq: f64 = stations
        .iter()
        .map(|[_, w, target]| (w - target).powi(2))
        .sum();
    let metrics = BeamMetrics {
        rms_percent: 100.0 * (sum_sq / stations.len() as f64).sqrt(),
        tip_deflection,
        voxels: grid.filled_count(),
        material_counts: grid.material_counts(scene.palette.len()),
        surface_voxels: surface.len(),
        profile,
        solver_iterations: solution.diagnostics.iterations,
        solver_residual: solution.diagnostics.relative_residual,
    };
    Outcome::evaluated(-sum_sq, Metrics::Beam(metrics))
}
