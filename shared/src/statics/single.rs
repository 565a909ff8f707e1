//! Single-precision copies of the multigrid's matrices, for the V-cycle only.
//!
//! The V-cycle is a preconditioner: CG needs it only to be a fixed, nearly symmetric positive
//! definite operator, not to be exact, and the outer compensated refinement (`solve.rs`) keeps
//! the answer at the requested residual. Its cost is memory traffic — each iteration streams
//! the fine matrix three times and the coarse ones as often, ~115 MB per iteration at 12×12×40 —
//! so storing its matrices and vectors in `f32` halves what it reads, and the fine matrix's
//! repeated blocks are read from one small table ([`super::bsr::DistinctBlocks`]).

use super::bsr::{BlockMatrix, DistinctBlocks};
use super::element::Block;
use super::wide::with_wide_vectors;

/// A 6×6 block in single precision, stored by columns: [`block32_mul_add`] then works on whole
/// columns, six rows at once in vector registers, where a row-major block needs a sequential sum
/// across each row.
pub(crate) type Block32 = [f32; 36];

/// A block sparse row matrix in single precision (see [`BlockMatrix`]), each distinct block
/// stored once where the double matrix knows them.
#[derive(Clone, Debug, Default)]
pub(crate) struct BlockMatrix32 {
    pub n: usize,
    row_ptr: Vec<u32>,
    cols: Vec<u32>,
    blocks: DistinctBlocks<Block32>,
}

/// The row-major double block rounded to single precision, stored by columns.
pub(crate) fn block32(b: &Block) -> Block32 {
    std::array::from_fn(|i| b[6 * (i % 6) + i / 6] as f32)
}

/// y += B x for a column-stored block. Each row's products are summed in column order and the
/// sum then added to y, exactly as [`super::bsr::block_mul_add`] sums a row-major block, so the
/// two give the same bits; only the layout differs.
#[inline(always)]
pub(crate) fn block32_mul_add(b: &Block32, x: &[f32], y: &mut [f32; 6]) {
    let x: &[f32; 6] = x.try_into().expect("six unknowns per node");
    let column = |k: usize| -> &[f32; 6] { b[6 * k..6 * k + 6].try_into().expect("block column") };
    let mut sum: [f32; 6] = std::array::from_fn(|r| column(0)[r] * x[0]);
    for (k, &xk) in x.iter().enumerate().skip(1) {
        for (s, &bk) in sum.iter_mut().zip(column(k)) {
            *s += bk * xk;
        }
    }
    for (yr, s) in y.iter_mut().zip(sum) {
        *yr += s;
    }
}

impl BlockMatrix32 {
    /// `a` rounded to single precision.
    pub fn from_f64(a: &BlockMatrix) -> Self {
        Self {
            n: a.n,
            row_ptr: a.row_ptr.iter().map(|&p| p as u32).collect(),
            cols: a.cols.clone(),
            blocks: match &a.distinct {
                Some(distinct) => distinct.map(block32),
                None => DistinctBlocks::whole(a.blocks.iter().map(block32).collect()),
            },
        }
    }

    /// The transpose of `a` (with `ncols` block columns) rounded to single precision: the
    /// restriction Pᵀ made straight from the prolongator. A column-stored block of Pᵀ holds the
    /// row-major values of the block of P it mirrors, so each block is only rounded.
    pub fn transpose_from_f64(a: &BlockMatrix, ncols: usize) -> Self {
        let mut row_ptr = vec![0u32; ncols + 1];
        for &c in &a.cols {
            row_ptr[c as usize + 1] += 1;
        }
        for k in 0..ncols {
            row_ptr[k + 1] += row_ptr[k];
        }
        let mut next = row_ptr.clone();
        let mut cols = vec![0u32; a.cols.len()];
        let mut blocks = vec![[0.0; 36]; a.cols.len()];
        for r in 0..a.n {
            let (a_cols, a_blocks) = a.row(r);
            for (&c, b) in a_cols.iter().zip(a_blocks) {
                let slot = &mut next[c as usize];
                cols[*slot as usize] = r as u32;
                blocks[*slot as usize] = b.map(|x| x as f32);
                *slot += 1;
            }
        }
        Self {
            n: ncols,
            row_ptr,
            cols,
            blocks: DistinctBlocks::whole(blocks),
        }
    }

    /// Row `r`'s block columns and blocks.
    #[inline(always)]
    pub fn row(&self, r: usize) -> impl Iterator<Item = (usize, &Block32)> {
        let range = self.row_ptr[r] as usize..self.row_ptr[r + 1] as usize;
        self.cols[range.clone()]
            .iter()
            .zip(range)
            .map(|(&c, k)| (c as usize, self.blocks.get(k)))
    }

    /// Row `r` of A x.
    #[inline(always)]
    fn row_product(&self, r: usize, x: &[f32]) -> [f32; 6] {
        let mut acc = [0.0; 6];
        for (c, b) in self.row(r) {
            block32_mul_add(b, &x[6 * c..6 * c + 6], &mut acc);
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
        inverse_diagonal: &DistinctBlocks<Block32>,
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
        inverse_diagonal: &DistinctBlocks<Block32>,
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
    fn relax(
        &self,
        inverse_diagonal: &DistinctBlocks<Block32>,
        b: &[f32],
        x: &mut [f32],
        i: usize,
    ) {
        let mut acc = [0.0; 6];
        for (c, block) in self.row(i) {
            if c != i {
                block32_mul_add(block, &x[6 * c..6 * c + 6], &mut acc);
            }
        }
        let r: [f32; 6] = std::array::from_fn(|k| b[6 * i + k] - acc[k]);
        let mut xi = [0.0; 6];
        block32_mul_add(inverse_diagonal.get(i), &r, &mut xi);
        x[6 * i..6 * i + 6].copy_from_slice(&xi);
    }
}

#[cfg(test)]
mod tests {
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::statics::bsr::block_mul_add;
    use crate::statics::element::transpose;

    #[test]
    fn a_column_stored_block_gives_the_row_major_products_bits() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..1000 {
            let b: Block = std::array::from_fn(|_| rng.random_range(-1.0e3..1.0e3));
            let x: [f32; 6] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
            let y0: [f32; 6] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
            let row_major = b.map(|v| v as f32);
            let (mut by_rows, mut by_columns) = (y0, y0);
            block_mul_add(&row_major, &x, &mut by_rows);
            block32_mul_add(&block32(&b), &x, &mut by_columns);
            assert_eq!(by_rows.map(f32::to_bits), by_columns.map(f32::to_bits));
        }
    }

    #[test]
    fn the_restriction_is_the_rounded_transpose_of_the_prolongator() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let (rows, ncols) = (50, 7);
        let mut p = BlockMatrix {
            n: rows,
            row_ptr: vec![0],
            ..Default::default()
        };
        let mut transposed: Vec<Vec<(u32, Block)>> = vec![Vec::new(); ncols];
        for r in 0..rows {
            let mut cols: Vec<u32> = (0..3).map(|_| rng.random_range(0..ncols as u32)).collect();
            cols.sort_unstable();
            cols.dedup();
            for c in cols {
                let b: Block = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
                transposed[c as usize].push((r as u32, transpose(&b)));
                p.cols.push(c);
                p.blocks.push(b);
            }
            p.row_ptr.push(p.cols.len());
        }
        let r = BlockMatrix32::transpose_from_f64(&p, ncols);
        assert_eq!(r.n, ncols);
        for (big_i, row) in transposed.iter().enumerate() {
            let stored: Vec<(usize, &Block32)> = r.row(big_i).collect();
            assert_eq!(stored.len(), row.len());
            for ((c, b), (expected_c, t)) in stored.into_iter().zip(row) {
                assert_eq!(c, *expected_c as usize);
                assert_eq!(b.map(f32::to_bits), block32(t).map(f32::to_bits));
            }
        }
    }
}
