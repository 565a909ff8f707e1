//! The voxel grid: a dense, flat array of optional materials over a box of `nx × ny × nz` cells.

use serde::{Deserialize, Serialize};

use crate::material::MaterialId;

/// Resolution of a workspace: voxel counts along X, Y and Z.
///
/// By the paper's convention a beam lies along +Y (clamped on the −Y layer) and gravity or load
/// acts along −Z.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct GridDims {
    pub nx: usize,
    pub ny: usize,
    pub nz: usize,
}

impl GridDims {
    pub const fn new(nx: usize, ny: usize, nz: usize) -> Self {
        Self { nx, ny, nz }
    }

    /// Number of cells, filled or not.
    pub const fn cell_count(&self) -> usize {
        self.nx * self.ny * self.nz
    }

    /// Flat index of cell (x, y, z); X varies fastest, then Y, then Z.
    #[inline]
    pub const fn index(&self, x: usize, y: usize, z: usize) -> usize {
        x + self.nx * (y + self.ny * z)
    }

    /// Cell coordinates of a flat index.
    #[inline]
    pub const fn coords(&self, index: usize) -> [usize; 3] {
        let x = index % self.nx;
        let yz = index / self.nx;
        [x, yz % self.ny, yz / self.ny]
    }

    /// Flat indices of the cell at `index` and of its up to 26 neighbours inside the grid (faces,
    /// edges and corners), in index order.
    pub fn neighbourhood(&self, index: usize) -> impl Iterator<Item = usize> + '_ {
        let [x, y, z] = self.coords(index);
        let span = |c: usize, n: usize| c.saturating_sub(1)..(c + 2).min(n);
        span(z, self.nz).flat_map(move |nz| {
            span(y, self.ny)
                .flat_map(move |ny| span(x, self.nx).map(move |nx| self.index(nx, ny, nz)))
        })
    }

    /// Centre of cell (x, y, z) in normalized workspace units ([0, 1] per axis).
    #[inline]
    pub fn normalized_centre(&self, x: usize, y: usize, z: usize) -> [f64; 3] {
        [
            (x as f64 + 0.5) / self.nx as f64,
            (y as f64 + 0.5) / self.ny as f64,
            (z as f64 + 0.5) / self.nz as f64,
        ]
    }
}

impl std::fmt::Display for GridDims {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}x{}", self.nx, self.ny, self.nz)
    }
}

/// A voxelized design: which cells are filled and with which material.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct VoxelGrid {
    dims: GridDims,
    cells: Vec<Option<MaterialId>>,
}

/// The six face directions, as unit offsets (−X, +X, −Y, +Y, −Z, +Z).
pub const FACE_OFFSETS: [[isize; 3]; 6] = [
    [-1, 0, 0],
    [1, 0, 0],
    [0, -1, 0],
    [0, 1, 0],
    [0, 0, -1],
    [0, 0, 1],
];

impl VoxelGrid {
    /// An empty grid.
    pub fn empty(dims: GridDims) -> Self {
        Self {
            dims,
            cells: vec![None; dims.cell_count()],
        }
    }

    /// A grid completely filled with one material.
    pub fn filled(dims: GridDims, material: MaterialId) -> Self {
        Self {
            dims,
            cells: vec![Some(material); dims.cell_count()],
        }
    }

    /// A grid from its flat cell array (X fastest, then Y, then Z).
    ///
    /// # Panics
    /// If `cells` does not hold exactly `dims.cell_count()` entries.
    pub fn from_cells(dims: GridDims, cells: Vec<Option<MaterialId>>) -> Self {
        assert_eq!(cells.len(), dims.cell_count(), "cell count must match dims");
        Self { dims, cells }
    }

    pub fn dims(&self) -> GridDims {
        self.dims
    }

    pub fn cells(&self) -> &[Option<MaterialId>] {
        &self.cells
    }

    /// Flat indices of the cells whose state (empty or a material) differs from one of their 26
    /// neighbours', in index order: where a one-voxel change of the design can happen.
    pub fn boundary_cells(&self) -> Vec<usize> {
        (0..self.dims.cell_count())
            .filter(|&i| {
                self.dims
                    .neighbourhood(i)
                    .any(|j| self.cells[j] != self.cells[i])
            })
            .collect()
    }

    #[inline]
    pub fn get(&self, x: usize, y: usize, z: usize) -> Option<MaterialId> {
        self.cells[self.dims.index(x, y, z)]
    }

    #[inline]
    pub fn set(&mut self, x: usize, y: usize, z: usize, material: Option<MaterialId>) {
        let i = self.dims.index(x, y, z);
        self.cells[i] = material;
    }

    /// Material at a signed coordinate, `None` outside the grid.
    #[inline]
    pub fn get_signed(&self, x: isize, y: isize, z: isize) -> Option<MaterialId> {
        let d = self.dims;
        if x < 0 || y < 0 || z < 0 {
            return None;
        }
        let (x, y, z) = (x as usize, y as usize, z as usize);
        if x >= d.nx || y >= d.ny || z >= d.nz {
            return None;
        }
        self.get(x, y, z)
    }

    /// Number of filled voxels.
    pub fn filled_count(&self) -> usize {
        self.cells.iter().filter(|c| c.is_some()).count()
    }

    /// Number of voxels of each material, indexed by material id.
    pub fn material_counts(&self, material_count: usize) -> Vec<usize> {
        let mut counts = vec![0; material_count];
        for m in self.cells.iter().flatten() {
            counts[m.index()] += 1;
        }
        counts
    }

    /// Flat indices of the filled voxels, in increasing order.
    pub fn filled_indices(&self) -> impl Iterator<Item = usize> + '_ {
        self.cells
            .iter()
            .enumerate()
            .filter_map(|(i, c)| c.map(|_| i))
    }
}

#[cfg(test)]
mod tests;
