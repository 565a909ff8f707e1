//! Voxelization of a Gaussian mixture (paper §I-D): per-material density fields are summed at
//! every voxel centre, the total is thresholded for the shape, and each filled voxel takes the
//! material of highest density.

use crate::genome::Genome;
use crate::material::MaterialId;

use super::grid::{GridDims, VoxelGrid};

/// Threshold on the total density above which a voxel is filled, used unless a scene says
/// otherwise. Point densities live in [−1, 1], so an isolated point with density above 0.5 makes a
/// blob and one below does not.
pub const DEFAULT_THRESHOLD: f64 = 0.5;

/// Per-axis factors that turn normalized workspace coordinates into units of the longest side, so a
/// point's falloff is a sphere in the physical workspace whatever its aspect ratio, and the same
/// genome gives the same shape at every resolution with that aspect ratio.
fn axis_scales(dims: GridDims) -> [f64; 3] {
    let longest = dims.nx.max(dims.ny).max(dims.nz) as f64;
    [
        dims.nx as f64 / longest,
        dims.ny as f64 / longest,
        dims.nz as f64 / longest,
    ]
}

/// The genome's per-material density fields on a rectangular lattice of sample positions, one
/// layer of constant z at a time: the voxelization samples voxel centres, a print samples the
/// printer's pitch, from the same continuous field.
///
/// A Gaussian with isotropic falloff factorises into one 1-D Gaussian per axis, so each point's x
/// and y profiles are tabulated once and a layer costs each point one exponential and then two
/// multiplications and an addition per sample.
#[derive(Debug)]
pub struct LayerSampler<'g> {
    genome: &'g Genome,
    scales: [f64; 3],
    material_count: usize,
    /// Per point: its x profile over the sample columns, then its y profile over the rows.
    profiles: Vec<f64>,
    columns: usize,
    rows: usize,
}

impl<'g> LayerSampler<'g> {
    /// Samples at normalized workspace coordinates `xs` × `ys` (each in [0, 1] inside the
    /// workspace; outside it the field simply continues) of a workspace shaped like `aspect`.
    pub fn new(
        genome: &'g Genome,
        aspect: GridDims,
        material_count: usize,
        xs: &[f64],
        ys: &[f64],
    ) -> Self {
        let scales = axis_scales(aspect);
        let mut profiles = Vec::with_capacity(genome.points.len() * (xs.len() + ys.len()));
        for point in &genome.points {
            let inv_two_var = 1.0 / (2.0 * point.falloff * point.falloff);
            for (axis, coordinates) in [xs, ys].into_iter().enumerate() {
                profiles.extend(coordinates.iter().map(|&u| {
                    let d = (u - point.position[axis]) * scales[axis];
                    (-d * d * inv_two_var).exp()
                }));
            }
        }
        LayerSampler {
            genome,
            scales,
            material_count,
            profiles,
            columns: xs.len(),
            rows: ys.len(),
        }
    }

    /// Samples in one layer.
    pub fn layer_len(&self) -> usize {
        self.columns * self.rows
    }

    /// Adds the layer at normalized height `z` into `out`, material-major with `stride` between
    /// materials: `out[k * stride + x + columns · y]`. Points are summed in genome order, so the
    /// result does not depend on how the caller walks the layers.
    pub fn accumulate_layer(&self, z: f64, out: &mut [f64], stride: usize) {
        let (nx, ny) = (self.columns, self.rows);
        assert!(
            stride >= nx * ny
                && out.len() >= self.material_count.saturating_sub(1) * stride + nx * ny
        );
        for (point, profiles) in self
            .genome
            .points
            .iter()
            .zip(self.profiles.chunks_exact(nx + ny))
        {
            let (gx, gy) = profiles.split_at(nx);
            let inv_two_var = 1.0 / (2.0 * point.falloff * point.falloff);
            let d = (z - point.position[2]) * self.scales[2];
            let wz = (-d * d * inv_two_var).exp() * point.density;
            let layer = &mut out[point.material.index() * stride..][..nx * ny];
            for (row, &wy) in layer.chunks_exact_mut(nx).zip(gy) {
                let wyz = wz * wy;
                for (cell, &wx) in row.iter_mut().zip(gx) {
                    *cell += wyz * wx;
                }
            }
        }
    }
}

/// Normalized coordinates of the cell centres along an axis of `n` cells.
fn cell_centres(n: usize) -> Vec<f64> {
    (0..n).map(|i| (i as f64 + 0.5) / n as f64).collect()
}

/// The per-material density fields of a genome at every voxel centre, laid out material-major:
/// `fields[k * cells + i]`.
pub fn density_fields(genome: &Genome, dims: GridDims, material_count: usize) -> Vec<f64> {
    let cells = dims.cell_count();
    let mut fields = vec![0.0; material_count * cells];
    let sampler = LayerSampler::new(
        genome,
        dims,
        material_count,
        &cell_centres(dims.nx),
        &cell_centres(dims.ny),
    );
    let layer = sampler.layer_len();
    for (z, &height) in cell_centres(dims.nz).iter().enumerate() {
        sampler.accumulate_layer(height, &mut fields[z * layer..], cells);
    }
    fields
}

/// The voxelization's rule for one sample, given each material's density there (`density(k)`):
/// filled when the total exceeds `threshold`, with the densest material, the lowest index on a
/// tie.
pub fn material_at(
    material_count: usize,
    threshold: f64,
    density: impl Fn(usize) -> f64,
) -> Option<MaterialId> {
    let mut total = 0.0;
    let mut best = (0, f64::NEG_INFINITY);
    for k in 0..material_count {
        let rho = density(k);
        total += rho;
        if rho > best.1 {
            best = (k, rho);
        }
    }
    (total > threshold).then_some(MaterialId(best.0 as u8))
}

/// Voxelizes a genome at the given resolution: filled where the summed density exceeds
/// `threshold`, with the material of highest density (the lowest index on a tie).
pub fn voxelize(
    genome: &Genome,
    dims: GridDims,
    material_count: usize,
    threshold: f64,
) -> VoxelGrid {
    let cells = dims.cell_count();
    let fields = density_fields(genome, dims, material_count);
    let cells_out = (0..cells)
        .map(|i| material_at(material_count, threshold, |k| fields[k * cells + i]))
        .collect();
    VoxelGrid::from_cells(dims, cells_out)
}

#[cfg(test)]
mod tests;
