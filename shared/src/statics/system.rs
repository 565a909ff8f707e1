//! The reduced linear system of one load case: the free nodes' block stiffness in scaled
//! unknowns (rotations times s), assembled link by link, and the scaled load vector.

use std::collections::HashMap;

use super::bsr::{BlockMatrix, DistinctBlocks};
use super::element::transpose;
use super::model::StaticModel;

const FIXED: u32 = u32::MAX;

/// `K̃ ũ = f̃` over the free nodes, with ũ = (u, s θ) and f̃ = (F, M / s).
#[derive(Clone, Debug)]
pub(crate) struct ReducedSystem {
    pub matrix: BlockMatrix,
    /// Model node of each reduced row.
    pub free_nodes: Vec<u32>,
    /// Voxel size s, the scale between rotations and scaled rotations.
    pub scale: f64,
}

impl ReducedSystem {
    /// Assembles the stiffness of the nodes not in `fixed` (a per-node flag).
    pub fn assemble(model: &StaticModel, fixed: &[bool]) -> Self {
        let n_nodes = model.node_count();
        let mut reduced = vec![FIXED; n_nodes];
        let mut free_nodes = Vec::new();
        for node in 0..n_nodes {
            if !fixed[node] {
                reduced[node] = free_nodes.len() as u32;
                free_nodes.push(node as u32);
            }
        }
        let n = free_nodes.len();
        let mut row_ptr = Vec::with_capacity(n + 1);
        let mut cols = Vec::with_capacity(7 * n);
        let mut blocks = Vec::with_capacity(7 * n);
        row_ptr.push(0);
        // A link kind's off-diagonal block sits at some k of `distinct` and its transpose at
        // k + 1, so k + side names the block a node sees (side 0: the node is the link's first).
        // A diagonal block sums the node's own link blocks in link order from zero, so the list
        // of k + side over its links names it too: equal lists, equal bits.
        let mut distinct = DistinctBlocks::default();
        let mut kind_of: HashMap<(u8, u64, u64), u32> = HashMap::new();
        let off_diagonal_of: Vec<u32> = (0..model.link_count())
            .map(|link| {
                *kind_of.entry(model.link_kind(link)).or_insert_with(|| {
                    let off = model.link_block(link, 1);
                    distinct.blocks.extend([off, transpose(&off)]);
                    distinct.blocks.len() as u32 - 2
                })
            })
            .collect();
        let mut diagonal_of: HashMap<[u32; 6], u32> = HashMap::new();
        let mut row: Vec<(u32, u32)> = Vec::with_capacity(7);
        for &node in &free_nodes {
            let node = node as usize;
            let links = model.node_links(node);
            assert!(links.len() <= 6, "a voxel has at most six face neighbours");
            let mut recipe = [u32::MAX; 6];
            row.clear();
            for (slot, &link) in recipe.iter_mut().zip(links) {
                let link = link as usize;
                let [i, j] = model.link_nodes(link);
                let kind = off_diagonal_of[link];
                let side = u32::from(i != node);
                *slot = kind + side;
                let other = if side == 0 { j } else { i };
                if reduced[other] != FIXED {
                    row.push((reduced[other], kind + side));
                }
            }
            let diagonal = *diagonal_of.entry(recipe).or_insert_with(|| {
                let mut diagonal = [0.0; 36];
                for &link in links {
                    let link = link as usize;
                    let which = if model.link_nodes(link)[0] == node {
                        0
                    } else {
                        2
                    };
                    for (d, o) in diagonal.iter_mut().zip(model.link_block(link, which)) {
                        *d += o;
                    }
                }
                distinct.blocks.push(diagonal);
                distinct.blocks.len() as u32 - 1
            });
            row.push((reduced[node], diagonal));
            row.sort_unstable_by_key(|&(c, _)| c);
            for &(c, k) in &row {
                cols.push(c);
                blocks.push(distinct.blocks[k as usize]);
                distinct.index.push(k);
            }
            row_ptr.push(cols.len());
        }
        Self {
            matrix: BlockMatrix {
                n,
                row_ptr,
                cols,
                blocks,
                distinct: Some(distinct),
            },
            free_nodes,
            scale: model.voxel_size(),
        }
    }

    /// Euclidean norm of a scaled vector of forces, in SI units (moments M = s M̃).
    pub fn si_force_norm(&self, scaled: &[f64]) -> f64 {
        let s2 = self.scale * self.scale;
        scaled
            .chunks_exact(6)
            .map(|v| {
                v[0] * v[0]
                    + v[1] * v[1]
                    + v[2] * v[2]
                    + s2 * (v[3] * v[3] + v[4] * v[4] + v[5] * v[5])
            })
            .sum::<f64>()
            .sqrt()
    }
}

#[cfg(test)]
mod tests {
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::material::{Material, MaterialId, Palette};
    use crate::statics::pcg::inverse_diagonal_blocks;
    use crate::statics::single::BlockMatrix32;
    use crate::voxel::{GridDims, VoxelGrid};

    /// A random three-material design with holes, its `y = 0` layer fixed, assembled.
    fn random_system(seed: u64) -> (StaticModel, ReducedSystem) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let dims = GridDims::new(5, 9, 4);
        let cells = (0..dims.cell_count())
            .map(|_| match rng.random_range(0..10) {
                0 => None,
                k => Some(MaterialId(k % 3)),
            })
            .collect();
        let palette = Palette(vec![
            Material::new("soft", 1.0e6, 0.35),
            Material::new("hard", 1.0e9, 0.35),
            Material::new("mid", 3.0e7, 0.45),
        ]);
        let model = StaticModel::new(&VoxelGrid::from_cells(dims, cells), &palette, 1e-3).unwrap();
        let fixed: Vec<bool> = (0..model.node_count())
            .map(|n| model.node_coords(n)[1] == 0)
            .collect();
        let system = ReducedSystem::assemble(&model, &fixed);
        (model, system)
    }

    /// The assembled blocks against the model's unreduced SI stiffness, built link by link by
    /// other code: K̃ = D⁻¹ K D⁻¹ with D = diag(1, 1, 1, s, s, s). A diagonal block sums up to
    /// six link blocks in another order, so entries agree to a few roundings of the largest.
    #[test]
    fn the_assembled_blocks_are_the_models_stiffness() {
        let (model, system) = random_system(7);
        let n_nodes = model.node_count();
        let mut dense = vec![0.0; 36 * n_nodes * n_nodes];
        let s = model.voxel_size();
        let scale = |k: usize| if k < 3 { 1.0 } else { s };
        for (row, col, value) in model.stiffness_triplets() {
            dense[row * 6 * n_nodes + col] += value / (scale(row % 6) * scale(col % 6));
        }
        let largest = dense.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let a = &system.matrix;
        let mut stored = 0;
        for r in 0..a.n {
            let (cols, blocks) = a.row(r);
            for (&c, block) in cols.iter().zip(blocks) {
                let (i, j) = (
                    system.free_nodes[r] as usize,
                    system.free_nodes[c as usize] as usize,
                );
                for (k, value) in block.iter().enumerate() {
                    let expected = dense[(6 * i + k / 6) * 6 * n_nodes + 6 * j + k % 6];
                    assert!((value - expected).abs() <= 8.0 * f64::EPSILON * largest);
                }
                stored += 1;
            }
        }
        // Every non-zero block between free nodes is stored: the diagonal and one per link.
        let free_links = (0..model.link_count())
            .filter(|&l| {
                let [i, j] = model.link_nodes(l);
                system.free_nodes.contains(&(i as u32)) && system.free_nodes.contains(&(j as u32))
            })
            .count();
        assert_eq!(stored, a.n + 2 * free_links);
    }

    /// Each stored block is its distinct block, bit for bit, and the off-diagonal ones come in
    /// at most one pair (a block and its transpose) per link kind: 3 axes × 6 material pairs.
    #[test]
    fn repeated_blocks_are_stored_once() {
        let (_, system) = random_system(11);
        let a = &system.matrix;
        let distinct = a
            .distinct
            .as_ref()
            .expect("an assembled matrix names its repeats");
        assert_eq!(distinct.index.len(), a.blocks.len());
        for (block, &k) in a.blocks.iter().zip(&distinct.index) {
            assert_eq!(
                block.map(f64::to_bits),
                distinct.blocks[k as usize].map(f64::to_bits)
            );
        }
        assert!(distinct.blocks.len() <= a.n + 2 * 3 * 6);
        assert!(a.blocks.len() > 3 * distinct.blocks.len() / 2);

        // One material, no holes: a node's diagonal block depends only on which of its six
        // neighbours exist, and along each axis that is one of three cases (below, above, both).
        let dims = GridDims::new(6, 8, 5);
        let model = StaticModel::new(
            &VoxelGrid::filled(dims, MaterialId(0)),
            &Palette(vec![Material::new("soft", 1.0e6, 0.35)]),
            1e-3,
        )
        .unwrap();
        let system = ReducedSystem::assemble(&model, &vec![false; model.node_count()]);
        let distinct = system.matrix.distinct.as_ref().unwrap();
        assert!(
            distinct.blocks.len() <= 2 * 3 + 3 * 3 * 3,
            "{}",
            distinct.blocks.len()
        );
    }

    /// Reading blocks from the distinct table changes no bit of a product, in double precision
    /// (CG) or in single (the V-cycle), nor of an inverse diagonal block.
    #[test]
    fn products_through_the_distinct_blocks_are_the_same_bits() {
        let (_, system) = random_system(13);
        let shared = &system.matrix;
        let whole = BlockMatrix {
            distinct: None,
            ..shared.clone()
        };
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let x: Vec<f64> = (0..shared.dof())
            .map(|_| rng.random_range(-1.0..1.0))
            .collect();
        let (mut y_shared, mut y_whole) = (vec![0.0; x.len()], vec![0.0; x.len()]);
        shared.mul_vec(&x, &mut y_shared);
        whole.mul_vec(&x, &mut y_whole);
        assert_eq!(
            y_shared.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            y_whole.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        let (inverse_shared, inverse_whole) = (
            inverse_diagonal_blocks(shared).unwrap(),
            inverse_diagonal_blocks(&whole).unwrap(),
        );
        for r in 0..shared.n {
            assert_eq!(
                inverse_shared.get(r).map(f64::to_bits),
                inverse_whole.get(r).map(f64::to_bits)
            );
        }
        let x32: Vec<f32> = x.iter().map(|&v| v as f32).collect();
        let (mut y_shared, mut y_whole) = (vec![0.0f32; x.len()], vec![0.0f32; x.len()]);
        BlockMatrix32::from_f64(shared).mul_vec(&x32, &mut y_shared);
        BlockMatrix32::from_f64(&whole).mul_vec(&x32, &mut y_whole);
        assert_eq!(
            y_shared.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            y_whole.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
    }
}
