//! Products of block sparse matrices for the Galerkin coarse operators.

use super::bsr::{BlockMatrix, block_gemm_add};
use super::wide::with_wide_vectors;

/// C = A B for block matrices, A with `a.n` rows and B with `ncols` block columns. Each row is
/// made in two passes: its sorted columns first, then its blocks, accumulated in place in C
/// through a dense marker from column to position. So every block is written once where it
/// stays, and the sums are taken in the order of A's and B's entries: deterministic.
pub(crate) fn multiply(a: &BlockMatrix, b: &BlockMatrix, ncols: usize) -> BlockMatrix {
    with_wide_vectors(
        #[inline(always)]
        || multiply_rows(a, b, ncols),
    )
}

#[inline(always)]
fn multiply_rows(a: &BlockMatrix, b: &BlockMatrix, ncols: usize) -> BlockMatrix {
    let mut marker = vec![usize::MAX; ncols];
    let mut row_ptr = Vec::with_capacity(a.n + 1);
    row_ptr.push(0);
    let mut cols: Vec<u32> = Vec::new();
    let mut blocks: Vec<[f64; 36]> = Vec::new();
    for r in 0..a.n {
        let start = cols.len();
        let (a_cols, a_blocks) = a.row(r);
        for &k in a_cols {
            for &c in b.row(k as usize).0 {
                if marker[c as usize] == usize::MAX {
                    marker[c as usize] = 0;
                    cols.push(c);
                }
            }
        }
        cols[start..].sort_unstable();
        for (position, &c) in cols.iter().enumerate().skip(start) {
            marker[c as usize] = position;
        }
        blocks.resize(cols.len(), [0.0; 36]);
        for (&k, a_block) in a_cols.iter().zip(a_blocks) {
            let (b_cols, b_blocks) = b.row(k as usize);
            for (&c, b_block) in b_cols.iter().zip(b_blocks) {
                block_gemm_add(a_block, b_block, &mut blocks[marker[c as usize]]);
            }
        }
        for &c in &cols[start..] {
            marker[c as usize] = usize::MAX;
        }
        row_ptr.push(cols.len());
    }
    BlockMatrix {
        n: a.n,
        row_ptr,
        cols,
        blocks,
    }
}
