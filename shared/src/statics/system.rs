//! The reduced linear system of one load case: the free nodes' block stiffness in scaled
//! unknowns (rotations times s), assembled link by link, and the scaled load vector.

use super::bsr::BlockMatrix;
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
        let mut row: Vec<(u32, [f64; 36])> = Vec::with_capacity(7);
        for &node in &free_nodes {
            let node = node as usize;
            let r = reduced[node];
            let mut diagonal = [0.0; 36];
            row.clear();
            for &link in model.node_links(node) {
                let link = link as usize;
                let [i, j] = model.link_nodes(link);
                let (own, other, off) = if i == node {
                    (model.link_block(link, 0), j, model.link_block(link, 1))
                } else {
                    (
                        model.link_block(link, 2),
                        i,
                        transpose(&model.link_block(link, 1)),
                    )
                };
                for (d, o) in diagonal.iter_mut().zip(own) {
                    *d += o;
                }
                if reduced[other] != FIXED {
                    row.push((reduced[other], off));
                }
            }
            row.push((r, diagonal));
            row.sort_unstable_by_key(|&(c, _)| c);
            for &(c, b) in &row {
                cols.push(c);
                blocks.push(b);
            }
            row_ptr.push(cols.len());
        }
        Self {
            matrix: BlockMatrix {
                n,
                row_ptr,
                cols,
                blocks,
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
