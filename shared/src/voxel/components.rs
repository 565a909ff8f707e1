//! Face-connected components: what of a voxelized design a task can use. A beam keeps the voxels
//! connected to its clamped layer; a robot keeps its largest body.

use super::grid::{FACE_OFFSETS, VoxelGrid};

/// Labels face-connected components of filled voxels: `labels[i]` is the component of voxel `i`
/// (`u32::MAX` for empty cells); components are numbered in order of their lowest voxel index.
/// Returns the labels and each component's size.
pub fn label_components(grid: &VoxelGrid) -> (Vec<u32>, Vec<usize>) {
    let dims = grid.dims();
    let mut labels = vec![u32::MAX; dims.cell_count()];
    let mut sizes = Vec::new();
    let mut stack = Vec::new();
    for seed in grid.filled_indices() {
        if labels[seed] != u32::MAX {
            continue;
        }
        let label = sizes.len() as u32;
        labels[seed] = label;
        stack.push(seed);
        let mut size = 0;
        while let Some(i) = stack.pop() {
            size += 1;
            for j in face_neighbours(grid, i) {
                if labels[j] == u32::MAX {
                    labels[j] = label;
                    stack.push(j);
                }
            }
        }
        sizes.push(size);
    }
    (labels, sizes)
}

/// Flat indices of the filled face neighbours of voxel `i`.
pub fn face_neighbours(grid: &VoxelGrid, i: usize) -> impl Iterator<Item = usize> + '_ {
    let dims = grid.dims();
    let [x, y, z] = dims.coords(i);
    FACE_OFFSETS.iter().filter_map(move |o| {
        let (nx, ny, nz) = (x as isize + o[0], y as isize + o[1], z as isize + o[2]);
        grid.get_signed(nx, ny, nz)
            .map(|_| dims.index(nx as usize, ny as usize, nz as usize))
    })
}

/// Keeps only the largest face-connected body (the lowest-numbered one on a tie).
pub fn keep_largest_component(grid: &VoxelGrid) -> VoxelGrid {
    let (labels, sizes) = label_components(grid);
    let Some(largest) = (0..sizes.len()).max_by_key(|&c| (sizes[c], std::cmp::Reverse(c))) else {
        return grid.clone();
    };
    keep_labels(grid, &labels, |l| l == largest as u32)
}

/// Keeps only the voxels face-connected to the layer `y = 0` (the clamped layer of a beam).
pub fn keep_connected_to_base(grid: &VoxelGrid) -> VoxelGrid {
    let dims = grid.dims();
    let (labels, sizes) = label_components(grid);
    let mut touches = vec![false; sizes.len()];
    for z in 0..dims.nz {
        for x in 0..dims.nx {
            let l = labels[dims.index(x, 0, z)];
            if l != u32::MAX {
                touches[l as usize] = true;
            }
        }
    }
    keep_labels(grid, &labels, |l| touches[l as usize])
}

fn keep_labels(grid: &VoxelGrid, labels: &[u32], keep: impl Fn(u32) -> bool) -> VoxelGrid {
    let cells = grid
        .cells()
        .iter()
        .zip(labels)
        .map(|(&c, &l)| if l != u32::MAX && keep(l) { c } else { None })
        .collect();
    VoxelGrid::from_cells(grid.dims(), cells)
}

#[cfg(test)]
mod tests;
