//! Single-precision copies of the multigrid's matrices, for the V-cycle only.
//!
//! The V-cycle is a preconditioner: CG needs it only to be a fixed, nearly symmetric positive
//! definite operator, not to be exact, and the outer compensated refinement (`solve.rs`) keeps
//! the answer at the requested residual. Its cost is memory traffic — each iteration streams
//! the fine matrix three times and the coarse ones as often, ~115 MB per iteration at 12×12×40 —
//! so storing its matrices and vectors in `f32` halves what it reads.

use super::bsr::{BlockMatrix, block_mul_add};
use super::element::Block;
use super::wide::with_wide_vectors;

/// A 6×6 block in single precision.
pub(crate) type Block32 = [f32; 36];

/// A block sparse row matrix in single precision (see [`BlockMatrix`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct BlockMatrix32 {
    pub n: usize,
    row_ptr: Vec<u32>,
    cols: Vec<u32>,
    blocks: Vec<Block32>,
}

/// The block rounded to single precision.
pub(crate) fn block32(b: &Block) -> Block32 {
    b.map(|x| x as f32)
}

impl BlockMatrix32 {
    /// `a` rounded to single precision.
    pub fn from_f64(a: &BlockMatrix) -> Self {
        Self {
            n: a.n,
            row_ptr: a.row_ptr.iter().map(|&p| p as u32).collect(),
            cols: a.cols.clone(),
            blocks: a.blocks.iter().map(block32).collect(),
        }
    }

    #[inline(always)]
    pub fn row(&self, r: usize) -> (&[u32], &[Block32]) {
        let range = self.row_ptr[r] as usize..self.row_ptr[r + 1] as usize;
        (&self.cols[range.clone()], &self.blocks[range])
    }

    /// Row `r` of A x.
    #[inline(always)]
    fn row_product(&self, r: usize, x: &[f32]) -> [f32; 6] {
        let (cols, blocks) = self.row(r);
        let mut acc = [0.0; 6];
        for (&c, b) in cols.iter().zip(blocks) {
            let c = 6 * c as usize;
            block_mul_add(b, &x[c..c + 6], &mut acc);
        }
        acc
    }

    /// y = A x.
    pub fn mul_vec(&self, x: &[f32], y: &mut [f32]) {
        with_wide_vectors(
            #[inline(always)]
            || {
                for (r, y_row) in y.chunks_exact_mut(6).enumerate() {
                    y_row.copy_from_slice(&self.row_product(r, x));
                }
            },
        )
    }

    /// y += A x.
    pub fn mul_vec_add(&self, x: &[f32], y: &mut [f32]) {
        with_wide_vectors(
            #[inline(always)]
            || {
                for (r, y_row) in y.chunks_exact_mut(6).enumerate() {
                    for (y, a) in y_row.iter_mut().zip(self.row_product(r, x)) {
                        *y += a;
                    }
                }
            },
        )
    }

    /// res = b − A x.
    pub fn residual(&self, b: &[f32], x: &[f32], res: &mut [f32]) {
        with_wide_vectors(
            #[inline(always)]
            || {
                for (r, res_row) in res.chunks_exact_mut(6).enumerate() {
                    for ((res, a), b) in res_row
                        .iter_mut()
                        .zip(self.row_product(r, x))
                        .zip(&b[6 * r..])
                    {
                        *res = b - a;
                    }
                }
            },
        )
    }

    /// One block Gauss–Seidel pass over the rows, forward or backward, with the inverted
    /// diagonal blocks `inverse_diagonal`.
    pub fn gauss_seidel(
        &self,
        inverse_diagonal: &[Block32],
        b: &[f32],
        x: &mut [f32],
        backward: bool,
    ) {
        with_wide_vectors(
            #[inline(always)]
            || self.gauss_seidel_pass(inverse_diagonal, b, x, backward),
        )
    }

    #[inline(always)]
    fn gauss_seidel_pass(
        &self,
        inverse_diagonal: &[Block32],
        b: &[f32],
        x: &mut [f32],
        backward: bool,
    ) {
        if backward {
            for i in (0..self.n).rev() {
                self.relax(inverse_diagonal, b, x, i);
            }
        } else {
            for i in 0..self.n {
                self.relax(inverse_diagonal, b, x, i);
            }
        }
    }

    /// Solves row `i` for its six unknowns, the other rows' held.
    #[inline(always)]
    fn relax(&self, inverse_diagonal: &[Block32], b: &[f32], x: &mut [f32], i: usize) {
        let (cols, blocks) = self.row(i);
        let mut acc = [0.0; 6];
        for (&c, block) in cols.iter().zip(blocks) {
            let c = c as usize;
            if c != i {
                block_mul_add(block, &x[6 * c..6 * c + 6], &mut acc);
            }
        }
        let r: [f32; 6] = std::array::from_fn(|k| b[6 * i + k] - acc[k]);
        let mut xi = [0.0; 6];
        block_mul_add(&inverse_diagonal[i], &r, &mut xi);
        x[6 * i..6 * i + 6].copy_from_slice(&xi);
    }
}
