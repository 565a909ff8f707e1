//! Products of block sparse matrices for the Galerkin coarse operators.

use super::bsr::{BlockMatrix, RowByRow, block_gemm_add};

/// C = A B for block matrices, A with `a.n` rows and B with `ncols` block columns. Each row of C
/// is accumulated in a scratch row indexed through a dense marker over C's columns, then copied
/// out in column order, so the result is deterministic and has sorted columns (and each block
/// is copied once, not pushed and then moved twice by the sort).
pub(crate) fn multiply(a: &BlockMatrix, b: &BlockMatrix, ncols: usize) -> BlockMatrix {
    let mut marker = vec![usize::MAX; ncols];
    let mut c_rows = RowByRow::with_capacity(a.n, 0);
    let mut row_cols: Vec<u32> = Vec::new();
    let mut row_blocks: Vec<[f64; 36]> = Vec::new();
    let mut order: Vec<(u32, usize)> = Vec::new();
    for r in 0..a.n {
        row_cols.clear();
        row_blocks.clear();
        let (a_cols, a_blocks) = a.row(r);
        for (&k, a_block) in a_cols.iter().zip(a_blocks) {
            let (b_cols, b_blocks) = b.row(k as usize);
            for (&c, b_block) in b_cols.iter().zip(b_blocks) {
                let slot = &mut marker[c as usize];
                if *slot == usize::MAX {
                    *slot = row_cols.len();
                    row_cols.push(c);
                    row_blocks.push([0.0; 36]);
                }
                block_gemm_add(a_block, b_block, &mut row_blocks[*slot]);
            }
        }
        order.clear();
        order.extend(row_cols.iter().enumerate().map(|(k, &c)| (c, k)));
        order.sort_unstable_by_key(|&(c, _)| c);
        c_rows.push_row(order.iter().map(|&(c, k)| (c, &row_blocks[k])));
        for &c in &row_cols {
            marker[c as usize] = usize::MAX;
        }
    }
    c_rows.finish()
}
