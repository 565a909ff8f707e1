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
        debug_assert!(
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
    voxelize_averaged(genome, dims, None, material_count, threshold)
}

/// Why `lattice` cannot refine `dims`: it must hold a whole number of lattice cells per voxel
/// along every axis.
pub fn check_lattice(dims: GridDims, lattice: GridDims) -> Result<(), String> {
    let axes = [
        ("x", dims.nx, lattice.nx),
        ("y", dims.ny, lattice.ny),
        ("z", dims.nz, lattice.nz),
    ];
    match axes.iter().find(|(_, n, l)| *n == 0 || *l % *n != 0) {
        Some((axis, n, l)) => Err(format!(
            "a density lattice of {l} cells along {axis} does not divide into {n} voxels"
        )),
        None => Ok(()),
    }
}

/// Every voxel's per-material density as the voxelization thresholds it, material-major
/// (`fields[k * cells + i]`): with a `lattice`, the mean of the field at the centres of the
/// lattice cells inside the voxel (a box filter of the continuous field); without one, or with
/// `lattice == dims`, the field at the voxel's centre (`density_fields`, bit for bit). With the
/// finest resolution of a run as the lattice, a coarse level's design is the fine design seen
/// through larger voxels rather than a point sample the search can tune to its grid
/// (docs/evolution.md, session 19). `lattice` must pass [`check_lattice`].
pub fn voxel_densities(
    genome: &Genome,
    dims: GridDims,
    lattice: Option<GridDims>,
    material_count: usize,
) -> Vec<f64> {
    let Some(lattice) = lattice.filter(|&l| l != dims) else {
        return density_fields(genome, dims, material_count);
    };
    let (rx, ry, rz) = (
        lattice.nx / dims.nx,
        lattice.ny / dims.ny,
        lattice.nz / dims.nz,
    );
    // The workspace keeps the voxel grid's aspect, so the field is the one `voxelize` samples.
    let sampler = LayerSampler::new(
        genome,
        dims,
        material_count,
        &cell_centres(lattice.nx),
        &cell_centres(lattice.ny),
    );
    let layer = sampler.layer_len();
    let cells = dims.cell_count();
    let mut sums = vec![0.0; material_count * cells];
    let mut samples = vec![0.0; material_count * layer];
    for (lz, &height) in cell_centres(lattice.nz).iter().enumerate() {
        samples.fill(0.0);
        sampler.accumulate_layer(height, &mut samples, layer);
        let z = lz / rz;
        for k in 0..material_count {
            let (from, to) = (
                &samples[k * layer..][..layer],
                &mut sums[k * cells..][..cells],
            );
            for ly in 0..lattice.ny {
                let row = &from[ly * lattice.nx..][..lattice.nx];
                for (lx, &rho) in row.iter().enumerate() {
                    to[dims.index(lx / rx, ly / ry, z)] += rho;
                }
            }
        }
    }
    let per_voxel = (rx * ry * rz) as f64;
    sums.iter_mut().for_each(|s| *s /= per_voxel);
    sums
}

/// What a unit-density point of `falloff` at a voxel's centre adds to that voxel's density in
/// [`voxel_densities`]: 1 without a lattice, else its Gaussian's mean over the voxel's lattice
/// centres (a product over the axes, since the Gaussian factorises).
pub fn centre_weight(dims: GridDims, lattice: Option<GridDims>, falloff: f64) -> f64 {
    let Some(lattice) = lattice else {
        return 1.0;
    };
    let scales = axis_scales(dims);
    [
        (dims.nx, lattice.nx),
        (dims.ny, lattice.ny),
        (dims.nz, lattice.nz),
    ]
    .iter()
    .zip(scales)
    .map(|(&(n, l), scale)| {
        let r = l / n;
        let mean: f64 = (0..r)
            .map(|i| {
                let offset = ((i as f64 + 0.5) / r as f64 - 0.5) / n as f64 * scale;
                (-offset * offset / (2.0 * falloff * falloff)).exp()
            })
            .sum();
        mean / r as f64
    })
    .product()
}

/// Voxelizes a genome at `dims` from [`voxel_densities`]: filled where the summed density
/// exceeds `threshold`, with the material of highest density (the lowest index on a tie).
pub fn voxelize_averaged(
    genome: &Genome,
    dims: GridDims,
    lattice: Option<GridDims>,
    material_count: usize,
    threshold: f64,
) -> VoxelGrid {
    let cells = dims.cell_count();
    let fields = voxel_densities(genome, dims, lattice, material_count);
    let cells_out = (0..cells)
        .map(|i| material_at(material_count, threshold, |k| fields[k * cells + i]))
        .collect();
    VoxelGrid::from_cells(dims, cells_out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::genome::GaussianPoint;

    fn blob(position: [f64; 3], density: f64, material: u8) -> GaussianPoint {
        GaussianPoint {
            position,
            density,
            falloff: 0.15,
            material: MaterialId(material),
        }
    }

    #[test]
    fn a_single_point_makes_a_centred_symmetric_blob() {
        let g = Genome::new(vec![blob([0.5, 0.5, 0.5], 1.0, 0)]);
        let grid = voxelize(&g, GridDims::new(10, 10, 10), 1, 0.5);
        assert!(grid.get(5, 5, 5).is_some());
        assert!(grid.get(0, 0, 0).is_none());
        for x in 0..10 {
            for y in 0..10 {
                for z in 0..10 {
                    assert_eq!(grid.get(x, y, z), grid.get(9 - x, y, z));
                    assert_eq!(grid.get(x, y, z), grid.get(x, z, y));
                }
            }
        }
    }

    #[test]
    fn a_negative_point_carves_a_hole() {
        let solid = Genome::new(vec![blob([0.5, 0.5, 0.5], 1.0, 0)]);
        let mut carved = solid.clone();
        carved.points.push(GaussianPoint {
            falloff: 0.1,
            ..blob([0.5, 0.5, 0.5], -1.0, 0)
        });
        let dims = GridDims::new(10, 10, 10);
        assert!(
            voxelize(&carved, dims, 1, 0.5).filled_count()
                < voxelize(&solid, dims, 1, 0.5).filled_count()
        );
    }

    #[test]
    fn each_voxel_takes_the_densest_material() {
        let g = Genome::new(vec![
            blob([0.2, 0.5, 0.5], 1.0, 0),
            blob([0.8, 0.5, 0.5], 1.0, 1),
        ]);
        let grid = voxelize(&g, GridDims::new(20, 10, 10), 2, 0.5);
        assert_eq!(grid.get(3, 5, 5), Some(MaterialId(0)));
        assert_eq!(grid.get(16, 5, 5), Some(MaterialId(1)));
    }

    /// Material `k`'s field at normalized position `c` of a workspace with axis scales `s`,
    /// summed point by point.
    fn direct_field(g: &Genome, c: [f64; 3], s: [f64; 3], k: usize) -> f64 {
        (g.points.iter())
            .filter(|p| p.material.index() == k)
            .map(|p| {
                let d2: f64 = (0..3)
                    .map(|a| ((c[a] - p.position[a]) * s[a]).powi(2))
                    .sum();
                p.density * (-d2 / (2.0 * p.falloff * p.falloff)).exp()
            })
            .sum()
    }

    #[test]
    fn separable_fields_match_the_direct_sum() {
        let g = Genome::new(vec![
            blob([0.3, 0.6, 0.1], 0.7, 0),
            blob([0.9, 0.2, 0.4], -0.4, 0),
        ]);
        let dims = GridDims::new(4, 6, 8);
        let fields = density_fields(&g, dims, 1);
        let s = axis_scales(dims);
        assert_eq!(fields.len(), dims.cell_count());
        for (i, &field) in fields.iter().enumerate() {
            let [x, y, z] = dims.coords(i);
            let direct = direct_field(&g, dims.normalized_centre(x, y, z), s, 0);
            assert!(
                (field - direct).abs() < 1e-12,
                "cell {i}: {field} vs {direct}"
            );
        }
    }

    /// A voxel of the averaged voxelization is filled, and with which material, by the mean of
    /// the field at the lattice cells inside it: checked against the Gaussians summed directly at
    /// each lattice centre (in the voxel grid's workspace) and averaged here, for random genomes,
    /// lattices 2 and 3 times finer, and unequal factors along the axes.
    #[test]
    fn an_averaged_voxel_takes_the_mean_of_its_lattice_cells() {
        use crate::genome::random_genome;
        use rand::SeedableRng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(19);
        let cases = [
            (GridDims::new(6, 20, 6), GridDims::new(12, 40, 12)),
            (GridDims::new(4, 4, 4), GridDims::new(12, 12, 12)),
            (GridDims::new(3, 5, 2), GridDims::new(6, 15, 2)),
        ];
        for (dims, lattice) in cases {
            let r = [
                lattice.nx / dims.nx,
                lattice.ny / dims.ny,
                lattice.nz / dims.nz,
            ];
            let per_voxel = (r[0] * r[1] * r[2]) as f64;
            for _ in 0..5 {
                let genome = random_genome(&mut rng, 30, &Default::default(), 2);
                let grid = voxelize_averaged(&genome, dims, Some(lattice), 2, 0.5);
                let mut means = vec![[0.0; 2]; dims.cell_count()];
                for j in 0..lattice.cell_count() {
                    let [x, y, z] = lattice.coords(j);
                    let c = lattice.normalized_centre(x, y, z);
                    let voxel = dims.index(x / r[0], y / r[1], z / r[2]);
                    for (k, m) in means[voxel].iter_mut().enumerate() {
                        *m += direct_field(&genome, c, axis_scales(dims), k) / per_voxel;
                    }
                }
                for (i, mean) in means.iter().enumerate() {
                    let total = mean[0] + mean[1];
                    // Skip cells within rounding of the threshold or of a material tie.
                    if (total - 0.5).abs() < 1e-9 || (mean[0] - mean[1]).abs() < 1e-9 {
                        continue;
                    }
                    let densest = MaterialId(u8::from(mean[1] > mean[0]));
                    let expected = (total > 0.5).then_some(densest);
                    assert_eq!(
                        grid.cells()[i],
                        expected,
                        "{dims:?} over {lattice:?}, cell {i}"
                    );
                }
            }
        }
    }

    /// Averaging is a box filter of a smooth field: a blob centred in the workspace stays mirror
    /// symmetric, and a lattice equal to the grid is the centre sample itself.
    #[test]
    fn averaging_keeps_symmetry_and_a_lattice_equal_to_the_grid_is_the_plain_voxelization() {
        let g = Genome::new(vec![blob([0.5, 0.5, 0.5], 1.0, 0)]);
        let dims = GridDims::new(6, 6, 6);
        let grid = voxelize_averaged(&g, dims, Some(GridDims::new(18, 18, 18)), 1, 0.5);
        assert!(grid.filled_count() > 0 && grid.filled_count() < dims.cell_count());
        for i in 0..dims.cell_count() {
            let [x, y, z] = dims.coords(i);
            assert_eq!(grid.get(x, y, z), grid.get(5 - x, y, z));
            assert_eq!(grid.get(x, y, z), grid.get(x, z, y));
        }
        assert_eq!(
            voxelize_averaged(&g, dims, Some(dims), 1, 0.5),
            voxelize(&g, dims, 1, 0.5)
        );
    }

    /// A unit point at a voxel's centre adds `centre_weight` to that voxel's averaged density.
    #[test]
    fn a_centred_points_share_of_its_voxel_is_the_centre_weight() {
        let (dims, lattice) = (GridDims::new(6, 20, 6), GridDims::new(18, 40, 12));
        let [x, y, z] = [2, 7, 4];
        let point = GaussianPoint {
            position: dims.normalized_centre(x, y, z),
            density: 1.0,
            falloff: 0.02,
            material: MaterialId(0),
        };
        let g = Genome::new(vec![point]);
        let averaged = voxel_densities(&g, dims, Some(lattice), 1)[dims.index(x, y, z)];
        let weight = centre_weight(dims, Some(lattice), 0.02);
        assert!((averaged - weight).abs() < 1e-14, "{averaged} vs {weight}");
        assert!(weight > 0.0 && weight < 1.0);
        assert_eq!(centre_weight(dims, None, 0.02), 1.0);
    }

    #[test]
    fn a_lattice_must_divide_into_the_voxels() {
        let dims = GridDims::new(6, 20, 6);
        assert!(check_lattice(dims, GridDims::new(12, 40, 12)).is_ok());
        assert!(check_lattice(dims, dims).is_ok());
        let err = check_lattice(dims, GridDims::new(12, 30, 12)).unwrap_err();
        assert!(
            err.contains("30 cells along y") && err.contains("20 voxels"),
            "{err}"
        );
    }
}
