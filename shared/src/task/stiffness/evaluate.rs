//! The stiffness evaluation: solve the cantilever, measure the tip's mean deflection, and score
//! stiffness within the hard-material budget.
//!
//! The fitness is lexicographic in one number: a design within its budget scores its tip
//! stiffness relative to the all-hard workspace (positive, larger is stiffer); a design over it
//! scores minus its excess hard fraction (negative). So every design within the budget ranks
//! above every design over it, and among those over it the smaller excess wins — the feasibility
//! rule of constrained evolutionary search, with no penalty weight to tune.

use super::scene::{StiffnessMetrics, StiffnessScene};
use crate::outcome::{Failure, Outcome};
use crate::task::cantilever::{layer_cells, solve_cantilever};
use crate::voxel::{GridDims, VoxelGrid};

/// Evaluates a kept design (its voxels face-connected to the clamped layer).
pub fn simulate_stiffness(grid: &VoxelGrid, scene: &StiffnessScene) -> Outcome<StiffnessMetrics> {
    let dims = grid.dims();
    let voxel_size = scene.length / dims.ny as f64;
    let solved = match solve_cantilever(
        grid,
        &scene.palette,
        voxel_size,
        scene.tip_load,
        &scene.solver,
    ) {
        Ok(s) => s,
        Err(failure) => return Outcome::failed(failure),
    };
    let tip: Vec<f64> = layer_cells(grid, dims.ny - 1)
        .map(|cell| -solved.displacement(cell)[2])
        .collect();
    let tip_deflection = tip.iter().sum::<f64>() / tip.len() as f64;
    if !(tip_deflection.is_finite() && tip_deflection > 0.0) {
        return Outcome::failed(Failure::Degenerate(format!(
            "tip deflection {tip_deflection:e} m is not downward"
        )));
    }
    let material_counts = grid.material_counts(scene.palette.len());
    let hard = material_counts[usize::from(scene.hard_material)];
    let hard_fraction = hard as f64 / dims.cell_count() as f64;
    let within_budget = hard_fraction <= scene.max_hard_fraction;
    let relative_stiffness = reference_deflection(scene, dims) / tip_deflection;
    let metrics = StiffnessMetrics {
        tip_deflection,
        relative_stiffness,
        hard_fraction,
        within_budget,
        voxels: grid.filled_count(),
        material_counts,
        flange_efficiency: flange_efficiency(grid, scene.hard_material),
        solver_iterations: solved.solution.diagnostics.iterations,
        solver_residual: solved.solution.diagnostics.relative_residual,
    };
    Outcome::evaluated(fitness(&metrics, scene), metrics)
}

/// The lexicographic fitness (see the module's documentation).
pub(super) fn fitness(m: &StiffnessMetrics, scene: &StiffnessScene) -> f64 {
    if m.within_budget {
        m.relative_stiffness
    } else {
        scene.max_hard_fraction - m.hard_fraction
    }
}

/// Euler–Bernoulli tip deflection of the whole workspace filled with the hard material:
/// P l³ / (3 E I) with I = b h³ / 12 of the full nx × nz section and l the lever arm from the
/// clamped layer's voxel centres to the loaded layer's, (ny − 1) voxels. It makes the fitness
/// dimensionless and comparable across scenes; a slender all-hard beam scores 1 (shear adds
/// well under 1 % at a slenderness of 20, test `task_stiffness`).
pub(super) fn reference_deflection(scene: &StiffnessScene, dims: GridDims) -> f64 {
    let s = scene.length / dims.ny as f64;
    let (b, h) = (dims.nx as f64 * s, dims.nz as f64 * s);
    let lever = (dims.ny - 1) as f64 * s;
    let e = scene.palette.0[usize::from(scene.hard_material)].youngs_modulus;
    let i = b * h.powi(3) / 12.0;
    scene.tip_load * lever.powi(3) / (3.0 * e * i)
}

/// Second moment of area of `n` unit cells about their centroid, from their row coordinates
/// (cell centres), each cell adding its own 1/12.
fn second_moment(rows: &[f64]) -> f64 {
    let n = rows.len() as f64;
    let mean = rows.iter().sum::<f64>() / n;
    rows.iter().map(|z| (z - mean).powi(2)).sum::<f64>() + n / 12.0
}

/// The rows of `n` cells packed as flanges into `nz` rows of `nx` cells: filled from the top
/// and bottom rows inwards, alternating, which maximises the second moment for the count.
fn flange_rows(n: usize, nx: usize, nz: usize) -> Vec<f64> {
    let mut rows = Vec::with_capacity(n);
    let (mut top, mut bottom) = (nz - 1, 0);
    while rows.len() < n && bottom <= top {
        if bottom == top {
            let k = (n - rows.len()).min(nx);
            rows.extend(std::iter::repeat_n(top as f64 + 0.5, k));
            break;
        }
        for i in 0..2 * nx {
            if rows.len() == n {
                break;
            }
            let row = if i % 2 == 0 { top } else { bottom };
            rows.push(row as f64 + 0.5);
        }
        top -= 1;
        bottom += 1;
    }
    rows
}

/// The hard-area-weighted mean, over the root half of the beam, of each layer's hard second
/// moment over the flanged layout's for the same count (see [`StiffnessMetrics`]).
pub(super) fn flange_efficiency(grid: &VoxelGrid, hard: u8) -> f64 {
    let dims = grid.dims();
    let (mut weighted, mut total) = (0.0, 0.0);
    for y in 0..dims.ny.div_ceil(2) {
        let rows: Vec<f64> = (0..dims.nz)
            .flat_map(|z| (0..dims.nx).map(move |x| (x, z)))
            .filter(|&(x, z)| grid.get(x, y, z).is_some_and(|m| m.0 == hard))
            .map(|(_, z)| z as f64 + 0.5)
            .collect();
        if rows.is_empty() {
            continue;
        }
        let ideal = second_moment(&flange_rows(rows.len(), dims.nx, dims.nz));
        let n = rows.len() as f64;
        weighted += n * second_moment(&rows) / ideal;
        total += n;
    }
    if total > 0.0 { weighted / total } else { 0.0 }
}

#[cfg(test)]
mod tests;
