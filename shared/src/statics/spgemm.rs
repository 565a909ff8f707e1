//! The Galerkin coarse operator Pᵀ A P of the multigrid setup.
//!
//! A P is never stored: at 12×40×12 it would be ~60,000 blocks (17 MB) written once and read
//! once. Each fine row of A P is made in a small buffer and scattered at once into the coarse
//! rows its P row reaches. Every coarse block on or above the diagonal receives its terms in the
//! order of the two-product form `(Pᵀ)(A P)`: over fine rows ascending, each term
//! Pᵢᴵᵀ (A P)ᵢᴶ, and each row of A P summed in the order of A's and P's entries. So the result is
//! deterministic and the same bits as that form there.
//!
//! A is symmetric, so Pᵀ A P is too: only the blocks with J ≥ I are summed, and each block below
//! the diagonal is the transpose of its mirror. That halves the scatter, the larger of the two
//! products, and makes the coarse operators symmetric to the bit.

use super::bsr::{BlockMatrix, block_gemm_add};
use super::element::{Block, transpose};
use super::wide::with_wide_vectors;

/// Pᵀ A P for a symmetric `a` and a prolongator `p` with `ncols` block columns.
pub(crate) fn galerkin_product(a: &BlockMatrix, p: &BlockMatrix, ncols: usize) -> BlockMatrix {
    let mut coarse = coarse_pattern(a, p, ncols);
    with_wide_vectors(
        #[inline(always)]
        || scatter_rows(a, p, &mut coarse),
    );
    mirror_upper_triangle(&mut coarse);
    coarse
}

/// The sparsity of Pᵀ A P, columns sorted in each row, blocks zero.
fn coarse_pattern(a: &BlockMatrix, p: &BlockMatrix, ncols: usize) -> BlockMatrix {
    // Coarse row I couples to J where some fine i has Pᵢᴵ ≠ 0 and (A P)ᵢᴶ ≠ 0: gather each
    // fine row's A P columns once, then hand them to every coarse row its P row reaches.
    let mut reach: Vec<Vec<u32>> = vec![Vec::new(); ncols];
    let mut marker = vec![false; ncols];
    let mut row_cols: Vec<u32> = Vec::new();
    for i in 0..a.n {
        row_cols.clear();
        for &k in a.row(i).0 {
            for &c in p.row(k as usize).0 {
                if !marker[c as usize] {
                    marker[c as usize] = true;
                    row_cols.push(c);
                }
            }
        }
        for &c in &row_cols {
            marker[c as usize] = false;
        }
        for &coarse_row in p.row(i).0 {
            reach[coarse_row as usize].extend_from_slice(&row_cols);
        }
    }
    let mut row_ptr = Vec::with_capacity(ncols + 1);
    row_ptr.push(0);
    let mut cols = Vec::new();
    for mut row in reach {
        row.sort_unstable();
        row.dedup();
        cols.extend_from_slice(&row);
        row_ptr.push(cols.len());
    }
    let blocks = vec![[0.0; 36]; cols.len()];
    BlockMatrix {
        distinct: None,
        n: ncols,
        row_ptr,
        cols,
        blocks,
    }
}

#[inline(always)]
fn scatter_rows(a: &BlockMatrix, p: &BlockMatrix, coarse: &mut BlockMatrix) {
    let mut position = vec![usize::MAX; coarse.n];
    let mut ap_cols: Vec<u32> = Vec::new();
    let mut ap_blocks: Vec<Block> = Vec::new();
    for i in 0..a.n {
        // Row i of A P, its columns sorted, summed over A's entries then P's.
        ap_cols.clear();
        let (a_cols, a_blocks) = a.row(i);
        for &k in a_cols {
            for &c in p.row(k as usize).0 {
                if position[c as usize] == usize::MAX {
                    position[c as usize] = 0;
                    ap_cols.push(c);
                }
            }
        }
        ap_cols.sort_unstable();
        for (slot, &c) in ap_cols.iter().enumerate() {
            position[c as usize] = slot;
        }
        ap_blocks.clear();
        ap_blocks.resize(ap_cols.len(), [0.0; 36]);
        for (&k, a_block) in a_cols.iter().zip(a_blocks) {
            let (p_cols, p_blocks) = p.row(k as usize);
            for (&c, p_block) in p_cols.iter().zip(p_blocks) {
                block_gemm_add(a_block, p_block, &mut ap_blocks[position[c as usize]]);
            }
        }
        for &c in &ap_cols {
            position[c as usize] = usize::MAX;
        }
        // Its share of every coarse row I that P's row i reaches, on and above the diagonal:
        // Pᵢᴵᵀ (A P)ᵢᴶ for J ≥ I. Both column lists are sorted, so one forward walk finds each
        // J's slot in the coarse row.
        let (p_cols, p_blocks) = p.row(i);
        for (&coarse_row, p_block) in p_cols.iter().zip(p_blocks) {
            let restriction = transpose(p_block);
            let start = coarse.row_ptr[coarse_row as usize];
            let end = coarse.row_ptr[coarse_row as usize + 1];
            let row_cols = &coarse.cols[start..end];
            let first = ap_cols.partition_point(|&c| c < coarse_row);
            let mut slot = 0;
            for (&c, ap_block) in ap_cols[first..].iter().zip(&ap_blocks[first..]) {
                slot += row_cols[slot..]
                    .iter()
                    .position(|&col| col == c)
                    .expect("the coarse pattern holds every product's column");
                block_gemm_add(&restriction, ap_block, &mut coarse.blocks[start + slot]);
            }
        }
    }
}

/// Sets every entry below the diagonal to its mirror above it: the blocks below the diagonal
/// to the transposes of theirs, and each diagonal block's lower triangle to its upper one.
fn mirror_upper_triangle(coarse: &mut BlockMatrix) {
    for row in 0..coarse.n {
        for k in coarse.row_ptr[row]..coarse.row_ptr[row + 1] {
            let col = coarse.cols[k] as usize;
            if col == row {
                let block = &mut coarse.blocks[k];
                for r in 1..6 {
                    for c in 0..r {
                        block[6 * r + c] = block[6 * c + r];
                    }
                }
            }
            if col >= row {
                break;
            }
            let mirror_start = coarse.row_ptr[col];
            let offset = coarse.cols[mirror_start..coarse.row_ptr[col + 1]]
                .binary_search(&(row as u32))
                .expect("the coarse pattern is symmetric");
            coarse.blocks[k] = transpose(&coarse.blocks[mirror_start + offset]);
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;

    fn random_block(rng: &mut ChaCha8Rng) -> Block {
        std::array::from_fn(|_| rng.random_range(-1.0..1.0))
    }

    /// A block matrix with `rows` rows and columns below `ncols`, each row holding `per_row`
    /// distinct random columns.
    fn random_matrix(
        rng: &mut ChaCha8Rng,
        rows: usize,
        ncols: usize,
        per_row: usize,
    ) -> BlockMatrix {
        let mut row_ptr = vec![0];
        let (mut cols, mut blocks) = (Vec::new(), Vec::new());
        for _ in 0..rows {
            let mut row: Vec<u32> = (0..per_row)
                .map(|_| rng.random_range(0..ncols as u32))
                .collect();
            row.sort_unstable();
            row.dedup();
            for c in row {
                cols.push(c);
                blocks.push(random_block(rng));
            }
            row_ptr.push(cols.len());
        }
        BlockMatrix {
            n: rows,
            row_ptr,
            cols,
            blocks,
            distinct: None,
        }
    }

    /// A = H + Hᵀ + I for a random H, stored in full: symmetric to the bit, diagonal stored.
    fn random_symmetric(rng: &mut ChaCha8Rng, n: usize, per_row: usize) -> BlockMatrix {
        let half = random_matrix(rng, n, n, per_row);
        let mut dense = vec![vec![None::<Block>; n]; n];
        for (i, row) in dense.iter_mut().enumerate() {
            row[i] = Some(std::array::from_fn(|k| if k % 7 == 0 { 1.0 } else { 0.0 }));
        }
        for i in 0..n {
            let (cols, blocks) = half.row(i);
            for (&j, b) in cols.iter().zip(blocks) {
                let j = j as usize;
                for (r, c, b) in [(i, j, *b), (j, i, transpose(b))] {
                    let sum = dense[r][c].get_or_insert([0.0; 36]);
                    sum.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                }
            }
        }
        let mut a = BlockMatrix {
            n,
            row_ptr: vec![0],
            ..Default::default()
        };
        for row in &dense {
            for (j, b) in row.iter().enumerate() {
                if let Some(b) = b {
                    a.cols.push(j as u32);
                    a.blocks.push(*b);
                }
            }
            a.row_ptr.push(a.cols.len());
        }
        a
    }

    /// Pᵀ A P as two stored products, A P then Pᵀ (A P), each sum in the order of the stored
    /// entries, every block summed on its own (no mirroring).
    fn two_products(a: &BlockMatrix, p: &BlockMatrix, nc: usize) -> Vec<Vec<Option<Block>>> {
        let mut ap = vec![vec![None::<Block>; nc]; a.n];
        for (i, ap_row) in ap.iter_mut().enumerate() {
            for (&k, a_block) in a.row(i).0.iter().zip(a.row(i).1) {
                for (&c, p_block) in p.row(k as usize).0.iter().zip(p.row(k as usize).1) {
                    let sum = ap_row[c as usize].get_or_insert([0.0; 36]);
                    block_gemm_add(a_block, p_block, sum);
                }
            }
        }
        let mut coarse = vec![vec![None::<Block>; nc]; nc];
        for (i, ap_row) in ap.iter().enumerate() {
            for (&big_i, p_block) in p.row(i).0.iter().zip(p.row(i).1) {
                let restriction = transpose(p_block);
                for (c, ap_block) in ap_row.iter().enumerate() {
                    if let Some(ap_block) = ap_block {
                        let sum = coarse[big_i as usize][c].get_or_insert([0.0; 36]);
                        block_gemm_add(&restriction, ap_block, sum);
                    }
                }
            }
        }
        coarse
    }

    #[test]
    fn the_galerkin_product_is_the_two_products_above_the_diagonal_and_their_mirror_below() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for (n, nc) in [(1, 1), (40, 9), (120, 17)] {
            let a = random_symmetric(&mut rng, n, 3);
            let p = random_matrix(&mut rng, n, nc, 3);
            let fused = galerkin_product(&a, &p, nc);
            let reference = two_products(&a, &p, nc);
            assert_eq!(fused.n, nc);
            // Σ|terms| of every entry, which bounds the rounding of any order of summation.
            let absolute = |m: &BlockMatrix| BlockMatrix {
                blocks: m.blocks.iter().map(|b| b.map(f64::abs)).collect(),
                distinct: None,
                ..m.clone()
            };
            let magnitudes = two_products(&absolute(&a), &absolute(&p), nc);
            for (big_i, reference_row) in reference.iter().enumerate() {
                let (cols, blocks) = fused.row(big_i);
                let expected: Vec<(u32, Block)> = (reference_row.iter().enumerate())
                    .filter_map(|(c, b)| b.map(|b| (c as u32, b)))
                    .collect();
                assert_eq!(
                    cols.len(),
                    expected.len(),
                    "row {big_i} of {n}x{nc}: pattern"
                );
                for ((&c, b), (ec, eb)) in cols.iter().zip(blocks).zip(&expected) {
                    assert_eq!(c, *ec, "row {big_i}: columns");
                    let magnitude = magnitudes[big_i][c as usize].expect("same pattern");
                    for (k, (x, y)) in b.iter().zip(eb).enumerate() {
                        let (row, col) = (6 * big_i + k / 6, 6 * c as usize + k % 6);
                        if col >= row {
                            assert_eq!(x.to_bits(), y.to_bits(), "({row}, {col})");
                        } else {
                            // The mirror and the entry summed on its own are each within h·ε·Σ|terms|
                            // of the exact value, where h, the most additions on any term's path
                            // (about 40 in a row of A P, then 6 per fine row reaching I), is
                            // below 1000 here.
                            let bound = 2.0 * 1000.0 * f64::EPSILON * magnitude[k];
                            assert!((x - y).abs() <= bound, "({row}, {col}): {x}, {y}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn the_galerkin_product_is_symmetric_to_the_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let a = random_symmetric(&mut rng, 60, 4);
        let p = random_matrix(&mut rng, 60, 8, 3);
        let coarse = galerkin_product(&a, &p, 8);
        let block = |i: usize, j: usize| -> Option<Block> {
            let (cols, blocks) = coarse.row(i);
            cols.iter()
                .position(|&c| c as usize == j)
                .map(|k| blocks[k])
        };
        for i in 0..8 {
            for j in 0..8 {
                let mirrored = block(j, i).map(|b| transpose(&b).map(f64::to_bits));
                assert_eq!(
                    block(i, j).map(|b| b.map(f64::to_bits)),
                    mirrored,
                    "({i}, {j})"
                );
            }
        }
    }
}
