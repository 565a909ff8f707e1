//! An evaluation's memory, estimated from its size before it starts, against a worker's budget
//! (`worker --max-memory`, by default half the machine's memory, shared by its threads; the
//! coordinator's local workers split that default between them). A task over budget is refused
//! with a message the coordinator records, and goes to another worker; no worker starts an
//! allocation it cannot finish (Rust aborts on allocation failure, and nothing can catch that).

use crate::task::Scene;
use crate::voxel::GridDims;

/// Memory an evaluation needs whatever its size (scene, genome, buffers).
const BASE_BYTES: u64 = 16 << 20;
/// The share of the machine's memory a worker uses when `--max-memory` is not given.
pub const DEFAULT_FRACTION: f64 = 0.5;

/// Estimated peak bytes of evaluating a design of `dims` in `scene`.
pub fn estimate(scene: &Scene, dims: GridDims) -> u64 {
    // Each task states its measured peak per voxel (docs/how-to/cluster.md).
    let per_voxel = scene.bytes_per_voxel();
    let voxels = (dims.nx as u64)
        .saturating_mul(dims.ny as u64)
        .saturating_mul(dims.nz as u64);
    BASE_BYTES.saturating_add(voxels.saturating_mul(per_voxel))
}

/// Total memory of this machine, from `/proc/meminfo` (None where there is none).
pub fn machine_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kib: u64 = text
        .lines()
        .find_map(|l| l.strip_prefix("MemTotal:"))?
        .trim()
        .strip_suffix("kB")?
        .trim()
        .parse()
        .ok()?;
    kib.checked_mul(1024)
}

/// The default budget of a whole worker: [`DEFAULT_FRACTION`] of the machine's memory, or 4 GiB
/// where it cannot be read.
pub fn default_budget() -> u64 {
    machine_memory().map_or(4 << 30, |m| (m as f64 * DEFAULT_FRACTION) as u64)
}

/// Parses `--max-memory`: bytes, or a number with a K, M, G or T suffix (powers of 1024).
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let (digits, shift) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => {
            let shift = match c.to_ascii_uppercase() {
                'K' => 10,
                'M' => 20,
                'G' => 30,
                'T' => 40,
                _ => return Err(format!("{text:?}: use bytes or a K, M, G or T suffix")),
            };
            (&t[..i], shift)
        }
        _ => (t, 0),
    };
    digits
        .parse::<u64>()
        .ok()
        .filter(|&n| n > 0)
        .and_then(|n| n.checked_mul(1 << shift))
        .ok_or_else(|| format!("{text:?} is not a positive size such as 8G or 512M"))
}

/// An evaluation whose estimated peak memory is over the budget it may use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "a {}x{}x{} evaluation needs about {:.2} GiB, over this worker's budget of {:.2} GiB per evaluation (its memory budget divided by its threads)",
    .dims.nx, .dims.ny, .dims.nz, gib(*.need), gib(*.budget)
)]
pub struct OverBudget {
    pub dims: GridDims,
    /// The estimate, bytes.
    pub need: u64,
    pub budget: u64,
}

fn gib(bytes: u64) -> f64 {
    bytes as f64 / f64::from(1u32 << 30)
}

/// Refuses an evaluation whose estimate exceeds `budget` bytes.
pub fn check(scene: &Scene, dims: GridDims, budget: u64) -> Result<(), OverBudget> {
    let need = estimate(scene, dims);
    if need <= budget {
        Ok(())
    } else {
        Err(OverBudget { dims, need, budget })
    }
}

#[cfg(test)]
mod tests;
