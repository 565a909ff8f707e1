//! Preconditioned conjugate gradients on the scaled system, stopped on the true SI residual.

use super::bsr::{BlockMatrix, block_mul_add, invert_spd_block};
use super::error::{Result, StaticsError};
use super::system::ReducedSystem;

/// A symmetric positive definite approximation of A⁻¹.
pub(crate) trait Precondition {
    /// z = M⁻¹ r.
    fn apply(&mut self, r: &[f64], z: &mut [f64]);
}

/// The inverse of every 6×6 diagonal block.
#[derive(Debug)]
pub(crate) struct BlockJacobi {
    inverse_diagonal: Vec<[f64; 36]>,
}

impl BlockJacobi {
    pub fn new(matrix: &BlockMatrix) -> Result<Self> {
        Ok(Self {
            inverse_diagonal: inverse_diagonal_blocks(matrix)?,
        })
    }
}

/// Inverse of each diagonal block; a block that is not SPD means a node without stiffness.
pub(crate) fn inverse_diagonal_blocks(matrix: &BlockMatrix) -> Result<Vec<[f64; 36]>> {
    matrix
        .diagonal_positions()
        .into_iter()
        .enumerate()
        .map(|(r, p)| {
            invert_spd_block(&matrix.blocks[p]).ok_or_else(|| {
                StaticsError::Factorization(format!(
                    "diagonal block of row {r} is not positive definite"
                ))
            })
        })
        .collect()
}

impl Precondition for BlockJacobi {
    fn apply(&mut self, r: &[f64], z: &mut [f64]) {
        for ((inv, r), z) in self
            .inverse_diagonal
            .iter()
            .zip(r.chunks_exact(6))
            .zip(z.chunks_exact_mut(6))
        {
            let mut acc = [0.0; 6];
            block_mul_add(inv, r, &mut acc);
            z.copy_from_slice(&acc);
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Outcome of a converged PCG run.
#[derive(Debug)]
pub(crate) struct PcgReport {
    pub iterations: usize,
    pub relative_residual: f64,
}

/// Solves `system.matrix x = rhs` from x = 0 until the true SI relative residual is at most
/// `tolerance`. The recurrence residual drifts from the true one in floating point, so when it
/// claims convergence the true residual is recomputed and, if short, CG restarts from it.
pub(crate) fn pcg(
    system: &ReducedSystem,
    rhs: &[f64],
    preconditioner: &mut dyn Precondition,
    tolerance: f64,
    max_iterations: usize,
    x: &mut [f64],
) -> Result<PcgReport> {
    let a = &system.matrix;
    let n = rhs.len();
    x.fill(0.0);
    let rhs_norm = system.si_force_norm(rhs);
    if rhs_norm == 0.0 {
        return Ok(PcgReport {
            iterations: 0,
            relative_residual: 0.0,
        });
    }
    let mut r = rhs.to_vec();
    let mut z = vec![0.0; n];
    let mut p = vec![0.0; n];
    let mut q = vec![0.0; n];
    let mut iterations = 0;
    'restart: loop {
        preconditioner.apply(&r, &mut z);
        p.copy_from_slice(&z);
        let mut rz = dot(&r, &z);
        while iterations < max_iterations {
            iterations += 1;
            a.mul_vec(&p, &mut q);
            let pq = dot(&p, &q);
            if !(pq > 0.0 && pq.is_finite()) {
                break;
            }
            let alpha = rz / pq;
            for ((xi, ri), (pi, qi)) in x.iter_mut().zip(r.iter_mut()).zip(p.iter().zip(&q)) {
                *xi += alpha * pi;
                *ri -= alpha * qi;
            }
            if system.si_force_norm(&r) <= tolerance * rhs_norm {
                let true_residual = system.relative_residual(x, rhs, &mut q);
                if true_residual <= tolerance {
                    return Ok(PcgReport {
                        iterations,
                        relative_residual: true_residual,
                    });
                }
                r.copy_from_slice(&q);
                continue 'restart;
            }
            preconditioner.apply(&r, &mut z);
            let rz_next = dot(&r, &z);
            let beta = rz_next / rz;
            rz = rz_next;
            for (pi, zi) in p.iter_mut().zip(&z) {
                *pi = zi + beta * *pi;
            }
        }
        // out of iterations, or a breakdown (pᵀAp ≤ 0: the preconditioner or matrix is not SPD)
        break;
    }
    let residual = system.relative_residual(x, rhs, &mut q);
    Err(StaticsError::NotConverged {
        iterations,
        residual,
        tolerance,
    })
}
