//! The multigrid's aggregates: the 2×2×2 blocks of the voxel grid, with small stiff clusters kept
//! whole.
//!
//! A small cluster of hard voxels inside soft ones moves almost as a rigid body: its own links are
//! a thousand times stiffer than the soft links around it. Cut across by 2×2×2 blocks, its pieces
//! land in different aggregates whose coarse unknowns are then bound together by those stiff
//! links, and the V-cycle converges slowly (designs with hard voxels scattered through soft ones
//! took several times the iterations of one-material designs). Moving each such cluster into one
//! aggregate lets a coarse node carry the cluster's rigid motion.

use super::bsr::BlockMatrix;

/// A link is stiff when its block is this many times the softest link's: far above the 2:1 of a
/// mixed hard–soft link against a soft one, far below the 1000:1 of the paper's two resins.
const STIFF_LINK_RATIO: f64 = 30.0;

/// The largest stiff cluster moved into one aggregate: eight nodes is a 2×2×2 block's worth, so
/// no aggregate grows past about twice the usual size; larger stiff regions are coarsened by the
/// grid's blocks like any other material.
const MAX_CLUSTER_NODES: usize = 8;

/// The aggregates of one level: the aggregate of each node, and each aggregate's coarse grid
/// coordinates. Aggregates are numbered in order of their first node.
pub(crate) fn grid_aggregates(coords: &[[u32; 3]]) -> (Vec<u32>, Vec<[u32; 3]>) {
    let mut extent = [0usize; 3];
    for c in coords {
        for (e, &ck) in extent.iter_mut().zip(c) {
            *e = (*e).max(ck as usize / 2 + 1);
        }
    }
    let mut id_of_key = vec![u32::MAX; extent[0] * extent[1] * extent[2]];
    let mut aggregate_of = Vec::with_capacity(coords.len());
    let mut coarse_coords = Vec::new();
    for c in coords {
        let key = [c[0] / 2, c[1] / 2, c[2] / 2];
        let flat = key[0] as usize + extent[0] * (key[1] as usize + extent[1] * key[2] as usize);
        if id_of_key[flat] == u32::MAX {
            id_of_key[flat] = coarse_coords.len() as u32;
            coarse_coords.push(key);
        }
        aggregate_of.push(id_of_key[flat]);
    }
    (aggregate_of, coarse_coords)
}

/// The largest magnitude in a block: for an axis-aligned frame link, its axial or bending
/// stiffness, either way proportional to the link's modulus.
fn link_strength(block: &[f64; 36]) -> f64 {
    block.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// The fine level's aggregates: the grid's blocks, then every connected cluster of 2 to
/// [`MAX_CLUSTER_NODES`] nodes joined by stiff links moved whole into the aggregate of its first
/// node. Aggregates left empty are dropped and the rest renumbered in order of their first node,
/// so a matrix without stiff links gets exactly [`grid_aggregates`].
pub(crate) fn fine_aggregates(a: &BlockMatrix, coords: &[[u32; 3]]) -> (Vec<u32>, Vec<[u32; 3]>) {
    let (mut aggregate_of, coarse_coords) = grid_aggregates(coords);
    let strength = |i: usize| {
        let (cols, blocks) = a.row(i);
        cols.iter()
            .zip(blocks)
            .filter(move |&(&j, _)| j as usize != i)
            .map(|(&j, b)| (j as usize, link_strength(b)))
    };
    let softest = (0..a.n)
        .flat_map(strength)
        .map(|(_, s)| s)
        .filter(|&s| s > 0.0)
        .fold(f64::INFINITY, f64::min);
    if !softest.is_finite() {
        return (aggregate_of, coarse_coords);
    }
    let stiff = STIFF_LINK_RATIO * softest;
    // Clusters by a depth-first walk over stiff links, started from each node in order, so
    // each cluster's first node is its lowest row.
    let mut cluster_of = vec![usize::MAX; a.n];
    let mut members = Vec::new();
    let mut stack = Vec::new();
    let mut moved = false;
    for start in 0..a.n {
        if cluster_of[start] != usize::MAX {
            continue;
        }
        members.clear();
        cluster_of[start] = start;
        stack.push(start);
        while let Some(i) = stack.pop() {
            members.push(i);
            for (j, s) in strength(i) {
                if s >= stiff && cluster_of[j] == usize::MAX {
                    cluster_of[j] = start;
                    stack.push(j);
                }
            }
        }
        if (2..=MAX_CLUSTER_NODES).contains(&members.len()) {
            let host = aggregate_of[start];
            for &i in &members {
                moved |= aggregate_of[i] != host;
                aggregate_of[i] = host;
            }
        }
    }
    if !moved {
        return (aggregate_of, coarse_coords);
    }
    let mut new_id = vec![u32::MAX; coarse_coords.len()];
    let mut kept = Vec::with_capacity(coarse_coords.len());
    for agg in aggregate_of.iter_mut() {
        let old = *agg as usize;
        if new_id[old] == u32::MAX {
            new_id[old] = kept.len() as u32;
            kept.push(coarse_coords[old]);
        }
        *agg = new_id[old];
    }
    (aggregate_of, kept)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::statics::bsr::RowByRow;

    /// A chain of nodes along x at the given coordinates, each joined to the next by a link of
    /// the given modulus (a diagonal block of the sum of its links').
    fn chain(xs: &[u32], moduli: &[f64]) -> (BlockMatrix, Vec<[u32; 3]>) {
        assert_eq!(moduli.len() + 1, xs.len());
        let link =
            |e: f64| -> [f64; 36] { std::array::from_fn(|k| if k % 7 == 0 { -e } else { 0.0 }) };
        let mut rows = RowByRow::with_capacity(xs.len(), 3 * xs.len());
        for i in 0..xs.len() {
            let left = (i > 0).then(|| moduli[i - 1]);
            let right = moduli.get(i).copied();
            let own = left.unwrap_or(0.0) + right.unwrap_or(0.0);
            let diagonal: [f64; 36] = std::array::from_fn(|k| if k % 7 == 0 { own } else { 0.0 });
            let mut row = Vec::new();
            if let Some(e) = left {
                row.push(((i - 1) as u32, link(e)));
            }
            row.push((i as u32, diagonal));
            if let Some(e) = right {
                row.push(((i + 1) as u32, link(e)));
            }
            rows.push_row(row.iter().map(|(c, b)| (*c, b)));
        }
        let coords = xs.iter().map(|&x| [x, 0, 0]).collect();
        (rows.finish(), coords)
    }

    #[test]
    fn one_material_gets_the_grid_blocks() {
        let xs: Vec<u32> = (0..9).collect();
        let (a, coords) = chain(&xs, &[1e6; 8]);
        assert_eq!(fine_aggregates(&a, &coords), grid_aggregates(&coords));
    }

    #[test]
    fn a_stiff_pair_across_two_blocks_shares_one_aggregate() {
        // Nodes 0..6 at x = 0..6; the hard link joins x = 3 and x = 4, which the grid puts in
        // blocks 1 and 2. The pair moves into block 1; block 2 keeps x = 5.
        let xs: Vec<u32> = (0..7).collect();
        let moduli = [1e6, 1e6, 2e6, 1e9, 2e6, 1e6];
        let (a, coords) = chain(&xs, &moduli);
        let (grid, _) = grid_aggregates(&coords);
        assert_eq!(grid, vec![0, 0, 1, 1, 2, 2, 3]);
        let (fine, coarse) = fine_aggregates(&a, &coords);
        assert_eq!(fine, vec![0, 0, 1, 1, 1, 2, 3]);
        assert_eq!(coarse, vec![[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]);
    }

    #[test]
    fn an_emptied_block_is_dropped_and_the_rest_renumbered() {
        // x = 1, 2 joined stiffly: x = 2 leaves block 1, which had no other node.
        let xs = [0, 1, 2, 4];
        let (a, coords) = chain(&xs, &[2e6, 1e9, 2e6]);
        let (fine, coarse) = fine_aggregates(&a, &coords);
        assert_eq!(fine, vec![0, 0, 0, 1]);
        assert_eq!(coarse, vec![[0, 0, 0], [2, 0, 0]]);
    }

    #[test]
    fn a_stiff_cluster_larger_than_a_block_keeps_the_grid_blocks() {
        let xs: Vec<u32> = (0..12).collect();
        let mut moduli = vec![1e9; 11];
        moduli[0] = 1e6;
        moduli[10] = 1e6;
        let (a, coords) = chain(&xs, &moduli);
        assert_eq!(fine_aggregates(&a, &coords), grid_aggregates(&coords));
    }
}
