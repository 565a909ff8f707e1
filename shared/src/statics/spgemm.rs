//! Products of block sparse matrices for the Galerkin coarse operators.

use super::bsr::{BlockMatrix, block_gemm_add};

/// C = A B for block matrices, A with `a.n` rows and B with `ncols` block columns. Each row of C
/// is accumulated in a dense marker over C's columns, then sorted, so the result is
/// deterministic and has sorted columns.
pub(crate) fn multiply(a: &BlockMatrix, b: &BlockMatrix, ncols: usize) -> BlockMatrix {
    let mut marker = vec![usize::MAX; ncols];
    let mut row_ptr = Vec::with_capacity(a.n + 1);
    let mut cols: Vec<u32> = Vec::new();
    let mut blocks: Vec<[f64; 36]> = Vec::new();
    let mut order: Vec<(u32, usize)> = Vec::new();
    let mut sorted: Vec<[f64; 36]> = Vec::new();
    row_ptr.push(0);
    for r in 0..a.n {
        let start = cols.len();
        let (a_cols, a_blocks) = a.row(r);
        for (&k, a_block) in a_cols.iter().zip(a_blocks) {
            let (b_cols, b_blocks) = b.row(k as usize);
            for (&c, b_block) in b_cols.iter().zip(b_blocks) {
                let slot = &mut marker[c as usize];
                if *slot == usize::MAX {
                    *slot = cols.len();
                    cols.push(c);
                    blocks.push([0.0; 36]);
                }
                block_gemm_add(a_block, b_block, &mut blocks[*slot]);
            }
        }
        // sort the row by column
        order.clear();
        order.extend(
            cols[start..]
                .iter()
                .enumerate()
                .map(|(k, &c)| (c, start + k)),
        );
        order.sort_unstable_by_key(|&(c, _)| c);
        sorted.clear();
        sorted.extend(order.iter().map(|&(_, k)| blocks[k]));
        for (k, (&(c, _), b)) in order.iter().zip(&sorted).enumerate() {
            cols[start + k] = c;
            blocks[start + k] = *b;
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
