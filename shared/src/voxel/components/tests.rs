use super::*;
use crate::material::MaterialId;
use crate::voxel::GridDims;

fn grid_with(dims: GridDims, filled: &[[usize; 3]]) -> VoxelGrid {
    let mut g = VoxelGrid::empty(dims);
    for &[x, y, z] in filled {
        g.set(x, y, z, Some(MaterialId(0)));
    }
    g
}

#[test]
fn diagonal_neighbours_are_separate_bodies() {
    let g = grid_with(GridDims::new(3, 3, 3), &[[0, 0, 0], [1, 1, 0], [1, 1, 1]]);
    let (_, sizes) = label_components(&g);
    assert_eq!(sizes, vec![1, 2]);
    assert_eq!(keep_largest_component(&g).filled_count(), 2);
}

#[test]
fn only_voxels_reaching_the_base_are_kept() {
    let g = grid_with(
        GridDims::new(2, 4, 1),
        &[[0, 0, 0], [0, 1, 0], [1, 3, 0], [0, 3, 0]],
    );
    let kept = keep_connected_to_base(&g);
    assert_eq!(kept.filled_count(), 2);
    assert!(kept.get(0, 3, 0).is_none());
}
