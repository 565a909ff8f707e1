//! How large a voxel grid Amorph accepts, in one place: a run config's resolution levels, a
//! task on the wire and `worker evaluate --resolution` are all checked here, so what a config
//! may ask for is exactly what a worker will take.
//!
//! 1 Mi voxels is 1.3 times the largest grid the benchmarks use (64x200x64) and 182 times the
//! paper's 12x40x12 beam. Counts arrive as `u64` so a config's 2^32 cannot wrap before the check.

use amorph::voxel::GridDims;

/// Largest voxel count along one axis.
pub const MAX_AXIS_VOXELS: u64 = 1024;
/// Largest voxel count of a whole grid.
pub const MAX_VOXELS: u64 = 1 << 20;

#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum GridSizeError {
    #[error("{axis} = {count} must be between 1 and {MAX_AXIS_VOXELS}")]
    Axis { axis: &'static str, count: u64 },
    #[error("{nx}x{ny}x{nz} = {total} voxels, at most {MAX_VOXELS}")]
    Total {
        nx: u64,
        ny: u64,
        nz: u64,
        total: u64,
    },
}

/// The grid of `[nx, ny, nz]`, or which count breaks which limit.
pub fn checked_grid(counts: [u64; 3]) -> Result<GridDims, GridSizeError> {
    for (axis, count) in ["nx", "ny", "nz"].into_iter().zip(counts) {
        if count == 0 || count > MAX_AXIS_VOXELS {
            return Err(GridSizeError::Axis { axis, count });
        }
    }
    let [nx, ny, nz] = counts;
    // At most 2^30 after the axis check: no overflow.
    let total = nx * ny * nz;
    if total > MAX_VOXELS {
        return Err(GridSizeError::Total { nx, ny, nz, total });
    }
    Ok(GridDims::new(nx as usize, ny as usize, nz as usize))
}

#[cfg(test)]
mod tests;
