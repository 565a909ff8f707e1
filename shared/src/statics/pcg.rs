//! Preconditioned conjugate gradients on the scaled system, stopped on the true SI residual.

use super::bsr::{BlockMatrix, DistinctBlocks, block_mul_add, invert_spd_block};
use super::error::{Result, StaticsError};
use super::system::ReducedSystem;
use super::wide::with_wide_vectors;

/// A symmetric positive definite approximation of A⁻¹.
pub(crate) trait Precondition {
    /// z = M⁻¹ r.
    fn apply(&mut self, r: &[f64], z: &mut [f64]);
}

/// The inverse of every 6×6 diagonal block.
#[derive(Debug)]
pub(crate) struct BlockJacobi {
    inverse_diagonal: DistinctBlocks,
}

impl BlockJacobi {
    pub fn new(matrix: &BlockMatrix) -> Result<Self> {
        Ok(Self {
            inverse_diagonal: inverse_diagonal_blocks(matrix)?,
        })
    }
}

/// Inverse of each row's diagonal block, each distinct block inverted once; a block that is not
/// SPD means a node without stiffness.
pub(crate) fn inverse_diagonal_blocks(matrix: &BlockMatrix) -> Result<DistinctBlocks> {
    let positions = matrix.diagonal_positions();
    let diagonal = match &matrix.distinct {
        Some(d) => {
            // Renumbered so that only the blocks on the diagonal are inverted.
            let mut renumbered = vec![u32::MAX; d.blocks.len()];
            let mut diagonal = DistinctBlocks::default();
            for &p in &positions {
                let k = d.index[p] as usize;
                if renumbered[k] == u32::MAX {
                    renumbered[k] = diagonal.blocks.len() as u32;
                    diagonal.blocks.push(d.blocks[k]);
                }
                diagonal.index.push(renumbered[k]);
            }
            diagonal
        }
        None => DistinctBlocks::whole(positions.iter().map(|&p| matrix.blocks[p]).collect()),
    };
    let mut inverse = Vec::with_capacity(diagonal.blocks.len());
    for (k, block) in diagonal.blocks.iter().enumerate() {
        let Some(block) = invert_spd_block(block) else {
            let row = diagonal
                .index
                .iter()
                .position(|&i| i as usize == k)
                .unwrap_or(k);
            return Err(StaticsError::Factorization(format!(
                "diagonal block of row {row} is not positive definite"
            )));
        };
        inverse.push(block);
    }
    Ok(DistinctBlocks {
        blocks: inverse,
        index: diagonal.index,
    })
}

impl Precondition for BlockJacobi {
    fn apply(&mut self, r: &[f64], z: &mut [f64]) {
        for (row, (r, z)) in r.chunks_exact(6).zip(z.chunks_exact_mut(6)).enumerate() {
            let mut acc = [0.0; 6];
            block_mul_add(self.inverse_diagonal.get(row), r, &mut acc);
            z.copy_from_slice(&acc);
        }
    }
}

#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solves `system.matrix x = rhs` from x = 0 until the recurrence residual is at most
/// `tolerance` of ‖rhs‖ (SI norms) and returns the iterations used. The recurrence drifts from
/// the true residual in floating point; the caller ([`super::solve`]'s refinement loop) measures
/// the true residual with compensated arithmetic and corrects from it, which also restarts CG.
pub(crate) fn pcg(
    system: &ReducedSystem,
    rhs: &[f64],
    preconditioner: &mut dyn Precondition,
    tolerance: f64,
    max_iterations: usize,
    x: &mut [f64],
) -> std::result::Result<usize, usize> {
    with_wide_vectors(
        #[inline(always)]
        || {
            let a = &system.matrix;
            let n = rhs.len();
            x.fill(0.0);
            let rhs_norm = system.si_force_norm(rhs);
            if rhs_norm == 0.0 {
                return Ok(0);
            }
            let mut r = rhs.to_vec();
            let mut z = vec![0.0; n];
            let mut q = vec![0.0; n];
            preconditioner.apply(&r, &mut z);
            let mut p = z.clone();
            let mut rz = dot(&r, &z);
            for iteration in 1..=max_iterations {
                a.mul_vec(&p, &mut q);
                let pq = dot(&p, &q);
                if !(pq > 0.0 && pq.is_finite()) {
                    // A breakdown: pᵀAp ≤ 0 means the preconditioner or the matrix is not SPD.
                    return Err(iteration);
                }
                let alpha = rz / pq;
                for ((xi, ri), (pi, qi)) in x.iter_mut().zip(r.iter_mut()).zip(p.iter().zip(&q)) {
                    *xi += alpha * pi;
                    *ri -= alpha * qi;
                }
                if system.si_force_norm(&r) <= tolerance * rhs_norm {
                    return Ok(iteration);
                }
                preconditioner.apply(&r, &mut z);
                let rz_next = dot(&r, &z);
                let beta = rz_next / rz;
                rz = rz_next;
                for (pi, zi) in p.iter_mut().zip(&z) {
                    *pi = zi + beta * *pi;
                }
            }
            Err(max_iterations)
        },
    )
}
