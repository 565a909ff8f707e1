//! Block sparse row (BSR) storage with 6×6 blocks: every node (or coarse aggregate) carries six
//! unknowns, so one column index serves 36 values and the inner loops are fixed-size.

use super::element::Block;
use super::wide::with_wide_vectors;

/// A square block-sparse matrix, full (not triangular) storage, columns sorted in each row.
#[derive(Clone, Debug, Default)]
pub(crate) struct BlockMatrix {
    /// Block rows.
    pub n: usize,
    pub row_ptr: Vec<usize>,
    pub cols: Vec<u32>,
    pub blocks: Vec<Block>,
    /// The same blocks stored once each, where the matrix knows them to repeat (an assembled
    /// matrix); `None` for products, whose blocks rarely repeat.
    pub distinct: Option<DistinctBlocks>,
}

/// Blocks that repeat, each stored once, and for every place that holds one (a stored block of
/// a matrix, a row's inverse diagonal block) its index among them.
///
/// An assembled stiffness matrix has one off-diagonal block per link, and a link's block depends
/// only on its axis and its two materials: a two-material beam at 12×40×12 holds ~28,000 such
/// blocks but 18 distinct ones, and ~70 distinct diagonal blocks among ~5,000. Reading them from
/// tables that stay in cache, instead of streaming 144 or 288 bytes per block from memory, is
/// what CG's products and the V-cycle's sweeps gain (physics.md); the values and the order of
/// every operation are unchanged, so are the bits.
#[derive(Clone, Debug)]
pub(crate) struct DistinctBlocks<B = Block> {
    pub blocks: Vec<B>,
    pub index: Vec<u32>,
}

impl<B> Default for DistinctBlocks<B> {
    fn default() -> Self {
        Self {
            blocks: Vec::new(),
            index: Vec::new(),
        }
    }
}

impl<B> DistinctBlocks<B> {
    /// Blocks that are not known to repeat: each its own index.
    pub fn whole(blocks: Vec<B>) -> Self {
        Self {
            index: (0..blocks.len() as u32).collect(),
            blocks,
        }
    }

    /// The block at place `k`.
    #[inline(always)]
    pub fn get(&self, k: usize) -> &B {
        &self.blocks[self.index[k] as usize]
    }

    /// Each distinct block converted once, at the same places.
    pub fn map<C>(&self, f: impl FnMut(&B) -> C) -> DistinctBlocks<C> {
        DistinctBlocks {
            blocks: self.blocks.iter().map(f).collect(),
            index: self.index.clone(),
        }
    }
}

/// y += B x for one row-major block (generic so that a test can set the column-stored single-
/// precision kernel of `single.rs` beside it).
#[inline(always)]
pub(crate) fn block_mul_add<T>(b: &[T; 36], x: &[T], y: &mut [T; 6])
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Mul<Output = T>,
{
    let x: &[T; 6] = x.try_into().expect("six unknowns per node");
    for (r, yr) in y.iter_mut().enumerate() {
        let row: &[T; 6] = b[6 * r..6 * r + 6].try_into().expect("block row");
        *yr = *yr
            + (row[0] * x[0]
                + row[1] * x[1]
                + row[2] * x[2]
                + row[3] * x[3]
                + row[4] * x[4]
                + row[5] * x[5]);
    }
}

/// C += A B for blocks. Each row of C is accumulated in registers over the six rows of B (the
/// Galerkin products of the multigrid setup spend most of their time here).
#[inline(always)]
pub(crate) fn block_gemm_add(a: &Block, b: &Block, c: &mut Block) {
    for (a_row, c_row) in a.chunks_exact(6).zip(c.chunks_exact_mut(6)) {
        let mut acc: [f64; 6] = c_row.try_into().expect("block row");
        for (&ark, b_row) in a_row.iter().zip(b.chunks_exact(6)) {
            for (acc, &bk) in acc.iter_mut().zip(b_row) {
                *acc += ark * bk;
            }
        }
        c_row.copy_from_slice(&acc);
    }
}

/// Builds a block matrix one row at a time, each row's blocks given in column order: the Galerkin
/// products and the smoothed prolongator both produce their rows that way.
#[derive(Debug)]
pub(crate) struct RowByRow {
    row_ptr: Vec<usize>,
    cols: Vec<u32>,
    blocks: Vec<Block>,
}

impl RowByRow {
    pub(crate) fn with_capacity(rows: usize, blocks: usize) -> Self {
        let mut row_ptr = Vec::with_capacity(rows + 1);
        row_ptr.push(0);
        Self {
            row_ptr,
            cols: Vec::with_capacity(blocks),
            blocks: Vec::with_capacity(blocks),
        }
    }

    /// Appends the next row; `row` must be sorted by column.
    #[inline(always)]
    pub(crate) fn push_row<'a>(&mut self, row: impl Iterator<Item = (u32, &'a Block)>) {
        let start = self.cols.len();
        for (c, b) in row {
            self.cols.push(c);
            self.blocks.push(*b);
        }
        assert!(
            self.cols[start..].windows(2).all(|w| w[0] < w[1]),
            "columns ascend"
        );
        self.row_ptr.push(self.cols.len());
    }

    pub(crate) fn finish(self) -> BlockMatrix {
        BlockMatrix {
            n: self.row_ptr.len() - 1,
            row_ptr: self.row_ptr,
            cols: self.cols,
            blocks: self.blocks,
            distinct: None,
        }
    }
}

impl BlockMatrix {
    /// Number of scalar rows.
    pub fn dof(&self) -> usize {
        6 * self.n
    }

    #[inline(always)]
    pub fn row(&self, r: usize) -> (&[u32], &[Block]) {
        let range = self.row_ptr[r]..self.row_ptr[r + 1];
        (&self.cols[range.clone()], &self.blocks[range])
    }

    /// y = A x, reading repeated blocks from [`DistinctBlocks`] where the matrix has them.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        match &self.distinct {
            Some(d) => self.mul_vec_by(x, y, |k| d.get(k)),
            None => self.mul_vec_by(x, y, |k| &self.blocks[k]),
        }
    }

    #[inline(always)]
    fn mul_vec_by<'a>(&self, x: &[f64], y: &mut [f64], block: impl Fn(usize) -> &'a Block) {
        with_wide_vectors(
            #[inline(always)]
            || {
                for (r, y_row) in y.chunks_exact_mut(6).enumerate() {
                    let mut acc = [0.0; 6];
                    for k in self.row_ptr[r]..self.row_ptr[r + 1] {
                        let c = self.cols[k] as usize;
                        block_mul_add(block(k), &x[6 * c..6 * c + 6], &mut acc);
                    }
                    y_row.copy_from_slice(&acc);
                }
            },
        )
    }

    /// r = f − A (x_hi + x_lo), every product and sum carried with its rounding error (FMA
    /// two-product, two-sum; Ogita, Rump & Oishi's compensated dot product). At 1e6:1 stiffness
    /// contrast ‖A‖‖x‖/‖f‖ reaches 1e9, so a plain double residual cannot resolve 1e-9 of ‖f‖:
    /// its cancellation error alone is ~1e-7. Compensated, the error falls to ~eps² ‖A‖‖x‖.
    pub fn residual_compensated(&self, f: &[f64], x_hi: &[f64], x_lo: &[f64], r: &mut [f64]) {
        with_wide_vectors(
            #[inline(always)]
            || self.residual_compensated_rows(f, x_hi, x_lo, r),
        )
    }

    #[inline(always)]
    fn residual_compensated_rows(&self, f: &[f64], x_hi: &[f64], x_lo: &[f64], r: &mut [f64]) {
        for (row, r_row) in r.chunks_exact_mut(6).enumerate() {
            let (cols, blocks) = self.row(row);
            for (k, rk) in r_row.iter_mut().enumerate() {
                let mut sum = f[6 * row + k];
                let mut err = 0.0;
                for (&c, b) in cols.iter().zip(blocks) {
                    let c = 6 * c as usize;
                    for (j, &a) in b[6 * k..6 * k + 6].iter().enumerate() {
                        let product = a * x_hi[c + j];
                        let product_err = a.mul_add(x_hi[c + j], -product);
                        let (s, e) = two_sum(sum, -product);
                        sum = s;
                        err += e - product_err - a * x_lo[c + j];
                    }
                }
                *rk = sum + err;
            }
        }
    }

    /// Position of the diagonal block of every row.
    pub fn diagonal_positions(&self) -> Vec<usize> {
        (0..self.n)
            .map(|r| {
                let (cols, _) = self.row(r);
                let k = cols
                    .binary_search(&(r as u32))
                    .expect("every row stores its diagonal block");
                self.row_ptr[r] + k
            })
            .collect()
    }
}

/// Inverts an SPD 6×6 block by Cholesky; `None` if it is not positive definite.
pub(crate) fn invert_spd_block(b: &Block) -> Option<Block> {
    let m = nalgebra::Matrix6::from_row_slice(b);
    let chol = m.cholesky()?;
    let inv = chol.inverse();
    let mut out = [0.0; 36];
    for r in 0..6 {
        for c in 0..6 {
            out[6 * r + c] = inv[(r, c)];
        }
    }
    Some(out)
}

/// a + b = s + e exactly (Knuth's two-sum, no ordering assumption).
#[inline(always)]
pub(crate) fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}
