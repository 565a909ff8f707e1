//! The static model of one design: node numbering of the filled voxels and the list of links with
//! their section stiffnesses, built once per design and shared by every load case.

use crate::material::{Palette, link_youngs_modulus};
use crate::voxel::{GridDims, VoxelGrid};

use super::element::LinkBlocks;
use super::error::{Result, StaticsError};

const NO_NODE: u32 = u32::MAX;

/// Nodes (filled voxels, in increasing flat-index order) and links (face-adjacent pairs) of a
/// voxel design, stored as flat arrays.
#[derive(Clone, Debug)]
pub struct StaticModel {
    dims: GridDims,
    voxel_size: f64,
    node_of_cell: Vec<u32>,
    cell_of_node: Vec<u32>,
    /// Per link: the lower node and the node one voxel further along `link_axis`.
    link_nodes: Vec<[u32; 2]>,
    link_axis: Vec<u8>,
    /// Per link: a = E s, the axial and bending stiffness scale of the scaled element (N/m).
    link_bend: Vec<f64>,
    /// Per link: g = G s / 6, the torsion stiffness scale of the scaled element (N/m).
    link_twist: Vec<f64>,
    /// Links of each node (CSR): `node_links[node_link_ptr[n]..node_link_ptr[n + 1]]`.
    node_link_ptr: Vec<u32>,
    node_links: Vec<u32>,
    pub(crate) blocks: LinkBlocks,
}

impl StaticModel {
    /// Numbers the filled voxels of `grid` and builds a frame element for every face-adjacent
    /// pair. `voxel_size` is the voxel edge in metres.
    pub fn new(grid: &VoxelGrid, palette: &Palette, voxel_size: f64) -> Result<Self> {
        if !(voxel_size.is_finite() && voxel_size > 0.0) {
            return Err(StaticsError::InvalidVoxelSize(voxel_size));
        }
        palette.validate()?;
        let dims = grid.dims();
        let mut node_of_cell = vec![NO_NODE; dims.cell_count()];
        let mut cell_of_node = Vec::new();
        for (cell, material) in grid.cells().iter().enumerate() {
            if let Some(m) = material {
                if m.index() >= palette.len() {
                    return Err(StaticsError::UnknownMaterial {
                        cell,
                        material: m.index(),
                        palette_len: palette.len(),
                    });
                }
                node_of_cell[cell] = cell_of_node.len() as u32;
                cell_of_node.push(cell as u32);
            }
        }
        if cell_of_node.is_empty() {
            return Err(StaticsError::EmptyModel);
        }

        let strides = [1, dims.nx, dims.nx * dims.ny];
        let extents = [dims.nx, dims.ny, dims.nz];
        let s = voxel_size;
        let mut model = Self {
            dims,
            voxel_size,
            node_of_cell,
            cell_of_node,
            link_nodes: Vec::new(),
            link_axis: Vec::new(),
            link_bend: Vec::new(),
            link_twist: Vec::new(),
            node_link_ptr: Vec::new(),
            node_links: Vec::new(),
            blocks: LinkBlocks::new(),
        };
        let cells = grid.cells();
        for (node, &cell) in model.cell_of_node.iter().enumerate() {
            let cell = cell as usize;
            let coords = dims.coords(cell);
            let m1 = palette.get(cells[cell].expect("node cell is filled"));
            for axis in 0..3 {
                if coords[axis] + 1 >= extents[axis] {
                    continue;
                }
                let other = cell + strides[axis];
                let Some(id2) = cells[other] else { continue };
                let m2 = palette.get(id2);
                let youngs = link_youngs_modulus(m1.youngs_modulus, m2.youngs_modulus);
                let poisson = 0.5 * (m1.poisson_ratio + m2.poisson_ratio);
                let shear = youngs / (2.0 * (1.0 + poisson));
                model
                    .link_nodes
                    .push([node as u32, model.node_of_cell[other]]);
                model.link_axis.push(axis as u8);
                model.link_bend.push(youngs * s);
                model.link_twist.push(shear * s / 6.0);
            }
        }
        model.build_node_links();
        Ok(model)
    }

    fn build_node_links(&mut self) {
        let n = self.cell_of_node.len();
        let mut counts = vec![0u32; n + 1];
        for &[i, j] in &self.link_nodes {
            counts[i as usize + 1] += 1;
            counts[j as usize + 1] += 1;
        }
        for k in 0..n {
            counts[k + 1] += counts[k];
        }
        let mut next = counts.clone();
        let mut links = vec![0u32; counts[n] as usize];
        for (l, &[i, j]) in self.link_nodes.iter().enumerate() {
            for node in [i, j] {
                links[next[node as usize] as usize] = l as u32;
                next[node as usize] += 1;
            }
        }
        self.node_link_ptr = counts;
        self.node_links = links;
    }

    /// Number of nodes (filled voxels).
    pub fn node_count(&self) -> usize {
        self.cell_of_node.len()
    }

    /// Number of links (face-adjacent pairs of filled voxels).
    pub fn link_count(&self) -> usize {
        self.link_nodes.len()
    }

    /// The node of a flat grid index, `None` for an empty or out-of-range cell.
    pub fn node_of_cell(&self, cell: usize) -> Option<usize> {
        match self.node_of_cell.get(cell) {
            Some(&n) if n != NO_NODE => Some(n as usize),
            _ => None,
        }
    }

    /// The flat grid index of a node.
    ///
    /// # Panics
    /// If `node >= node_count()`.
    pub fn cell_of_node(&self, node: usize) -> usize {
        self.cell_of_node[node] as usize
    }

    /// Grid coordinates (x, y, z) of a node.
    pub fn node_coords(&self, node: usize) -> [usize; 3] {
        self.dims.coords(self.cell_of_node(node))
    }

    pub fn dims(&self) -> GridDims {
        self.dims
    }

    /// Voxel edge length in metres.
    pub fn voxel_size(&self) -> f64 {
        self.voxel_size
    }

    pub(crate) fn link_nodes(&self, link: usize) -> [usize; 2] {
        let [i, j] = self.link_nodes[link];
        [i as usize, j as usize]
    }

    pub(crate) fn node_links(&self, node: usize) -> &[u32] {
        &self.node_links[self.node_link_ptr[node] as usize..self.node_link_ptr[node + 1] as usize]
    }

    /// Block `which` (0 = ii, 1 = ij, 2 = jj) of a link in scaled unknowns.
    pub(crate) fn link_block(&self, link: usize, which: usize) -> [f64; 36] {
        self.blocks.block(
            usize::from(self.link_axis[link]),
            which,
            self.link_bend[link],
            self.link_twist[link],
        )
    }

    /// What a link's blocks depend on besides its nodes: its axis and its two stiffnesses (bits).
    /// Links of one kind have the same blocks, bit for bit.
    pub(crate) fn link_kind(&self, link: usize) -> (u8, u64, u64) {
        (
            self.link_axis[link],
            self.link_bend[link].to_bits(),
            self.link_twist[link].to_bits(),
        )
    }

    /// The unreduced global stiffness in SI units (forces in N, moments in N·m per m and per rad)
    /// as `(row, col, value)` triplets with DOF `6 * node + k`, duplicates summed by the reader.
    /// For tests and exports; the solver never forms it.
    pub fn stiffness_triplets(&self) -> Vec<(usize, usize, f64)> {
        let s = self.voxel_size;
        // K = D K̃ D with D = diag(1, 1, 1, s, s, s) undoes the rotation scaling θ̃ = s θ.
        let scale = |k: usize| if k < 3 { 1.0 } else { s };
        let mut triplets = Vec::with_capacity(self.link_count() * 4 * 36);
        for link in 0..self.link_count() {
            let [i, j] = self.link_nodes(link);
            let kij = self.link_block(link, 1);
            for (row_node, col_node, block) in [
                (i, i, self.link_block(link, 0)),
                (i, j, kij),
                (j, i, super::element::transpose(&kij)),
                (j, j, self.link_block(link, 2)),
            ] {
                for r in 0..6 {
                    for c in 0..6 {
                        let v = block[6 * r + c];
                        if v != 0.0 {
                            triplets.push((
                                6 * row_node + r,
                                6 * col_node + c,
                                v * scale(r) * scale(c),
                            ));
                        }
                    }
                }
            }
        }
        triplets
    }
}
