//! The beam's evaluation: clamp the −Y layer, load the free-end layer downward, solve the statics,
//! and score how closely the deflected top surface follows the target profile.

use super::scene::{BeamMetrics, BeamScene};
use crate::outcome::{Failure, Outcome};
use crate::task::cantilever::solve_cantilever;
use crate::voxel::VoxelGrid;

/// Evaluates a kept design (its voxels face-connected to the clamped layer).
pub fn simulate_beam(grid: &VoxelGrid, scene: &BeamScene) -> Outcome<BeamMetrics> {
    let dims = grid.dims();
    let tip_y = dims.ny - 1;
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

    // The top surface: the highest voxel of every (x, y) column; its downward deflection is −u_z
    // (a small rotation moves the top face sideways, not vertically).
    let surface: Vec<(usize, f64)> = (1..dims.ny)
        .flat_map(|y| (0..dims.nx).map(move |x| (x, y)))
        .filter_map(|(x, y)| {
            let z = (0..dims.nz).rev().find(|&z| grid.get(x, y, z).is_some())?;
            let u = solved.displacement(dims.index(x, y, z));
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
        solver_iterations: solved.solution.diagnostics.iterations,
        solver_residual: solved.solution.diagnostics.relative_residual,
    };
    Outcome::evaluated(-sum_sq, metrics)
}
