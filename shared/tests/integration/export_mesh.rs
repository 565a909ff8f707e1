//! Per-material surface meshes and STL: closed, manifold, consistently oriented, of the right
//! volume, and round-tripping through binary STL.

use std::collections::HashMap;

use amorph::export::{
    TriangleMesh, boundary_mesh, material_meshes_mm, read_binary_stl, write_binary_stl,
};
use amorph::material::MaterialId;
use amorph::voxel::{GridDims, VoxelGrid};
use proptest::prelude::*;

use crate::common::grid_from;

/// Checks the mesh is a closed oriented 2-manifold surface: every undirected edge is used by
/// exactly two triangles, once in each direction, and no two vertices share a position (so the
/// position-based STL is manifold too).
fn assert_closed_manifold(mesh: &TriangleMesh) -> Result<(), String> {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &count) in &directed {
        if count != 1 {
            return Err(format!("directed edge {a}->{b} used {count} times"));
        }
        if directed.get(&(b, a)) != Some(&1) {
            return Err(format!("edge {a}->{b} has no opposite"));
        }
    }
    let mut seen = HashMap::new();
    for (i, v) in mesh.vertices.iter().enumerate() {
        let key = v.map(f64::to_bits);
        if let Some(j) = seen.insert(key, i) {
            return Err(format!("vertices {j} and {i} coincide at {v:?}"));
        }
    }
    Ok(())
}

#[test]
fn a_single_voxel_is_a_cube_of_twelve_triangles_and_volume_s_cubed() {
    let grid = VoxelGrid::filled(GridDims::new(1, 1, 1), MaterialId(0));
    let mesh = boundary_mesh(&grid, 0.002, |c| c.is_some());
    assert_eq!(mesh.triangles.len(), 12);
    assert_eq!(mesh.vertices.len(), 8);
    assert_closed_manifold(&mesh).unwrap();
    assert!((mesh.volume() - 8e-9).abs() < 1e-20);
}

/// Two voxels touching along an edge only: the mesh splits the edge into two (6-connected
/// reading), stays manifold, and loses only the pinch offset's sliver of volume.
#[test]
fn voxels_touching_along_an_edge_give_two_manifold_sheets() {
    let dims = GridDims::new(2, 2, 1);
    let grid = grid_from(dims, &[1, 0, 0, 1]);
    let mesh = boundary_mesh(&grid, 1.0, |c| c.is_some());
    assert_eq!(mesh.triangles.len(), 24);
    assert_closed_manifold(&mesh).unwrap();
    assert!((mesh.volume() - 2.0).abs() < 1e-2, "{}", mesh.volume());
}

#[test]
fn stl_round_trips_every_triangle_in_millimetres() {
    let dims = GridDims::new(3, 2, 2);
    let grid = grid_from(dims, &[1, 2, 1, 0, 1, 2, 2, 1, 0, 1, 1, 2]);
    let meshes = material_meshes_mm(&grid, 2, 1e-3);
    for mesh in &meshes {
        let mut bytes = Vec::new();
        write_binary_stl(mesh, "amorph test", &mut bytes).unwrap();
        assert_eq!(bytes.len(), 84 + 50 * mesh.triangles.len());
        let back = read_binary_stl(&mut bytes.as_slice()).unwrap();
        assert_eq!(back.len(), mesh.triangles.len());
        for (t, b) in mesh.triangles.iter().zip(&back) {
            for (k, &i) in t.iter().enumerate() {
                let v = mesh.vertices[i as usize];
                for a in 0..3 {
                    assert_eq!(b[k][a], v[a] as f32);
                }
            }
        }
    }
}

/// Coplanar faces merge: a 10×10×10 block's six sides become six rectangles whose borders meet
/// only at the block's corners, so each is two triangles: 12 instead of 1,200, same closed
/// surface and volume.
#[test]
fn a_block_merges_into_six_rectangles() {
    let grid = VoxelGrid::filled(GridDims::new(10, 10, 10), MaterialId(0));
    let mesh = &material_meshes_mm(&grid, 1, 1e-3)[0];
    assert_eq!(mesh.triangles.len(), 12);
    assert_eq!(mesh.vertices.len(), 8);
    assert_closed_manifold(mesh).unwrap();
    assert!((mesh.volume() - 1000.0).abs() < 1e-9);
}

/// A staircase: each step's top rectangle meets the riser below it and the step beside it at
/// points in the middle of its sides (T-junctions if not split); the merged mesh stays closed
/// and smaller than the unmerged one.
#[test]
fn a_staircase_merges_without_t_junctions() {
    let dims = GridDims::new(6, 4, 6);
    let cells = (0..dims.cell_count())
        .map(|i| {
            let [x, y, z] = dims.coords(i);
            (z <= x && !(y == 3 && x % 2 == 0)).then_some(MaterialId(0))
        })
        .collect();
    let grid = VoxelGrid::from_cells(dims, cells);
    let merged = &material_meshes_mm(&grid, 1, 1e-3)[0];
    let unmerged = boundary_mesh(&grid, 1.0, |c| c.is_some());
    assert_closed_manifold(merged).unwrap();
    assert!((merged.volume() - grid.filled_count() as f64).abs() < 1e-9);
    assert!(
        merged.triangles.len() * 2 < unmerged.triangles.len(),
        "{} vs {} triangles",
        merged.triangles.len(),
        unmerged.triangles.len()
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(100))]

    /// Dense random 6×6×6 designs (long coplanar runs to merge, with holes and pinches): the
    /// merged meshes stay closed, manifold, oriented and of the right volume.
    #[test]
    fn merged_meshes_of_dense_designs_stay_closed(
        cells in prop::collection::vec(prop::sample::select(vec![0u8, 1, 1, 1, 2, 2, 2]), 216),
    ) {
        let dims = GridDims::new(6, 6, 6);
        let grid = grid_from(dims, &cells);
        for (m, mesh) in material_meshes_mm(&grid, 2, 1e-3).iter().enumerate() {
            let count = cells.iter().filter(|&&c| c == m as u8 + 1).count();
            if let Err(e) = assert_closed_manifold(mesh) {
                prop_assert!(false, "material {m}: {e}");
            }
            let volume = mesh.volume();
            prop_assert!((volume - count as f64).abs() <= 1e-2 * (count as f64).max(1.0));
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Random two-material 4x4x4 designs (many edge and corner contacts): each material's mesh
    /// is closed, manifold and consistently oriented, and encloses its voxel count times s³ up to
    /// the pinch offsets (each moves a vertex by 1e-3 s, changing the volume by less than
    /// 1e-3 s³ per adjacent face; 1 % of the volume bounds it for these sizes).
    #[test]
    fn material_meshes_are_closed_manifolds_of_the_right_volume(
        cells in prop::collection::vec(0u8..3, 64),
    ) {
        let dims = GridDims::new(4, 4, 4);
        let grid = grid_from(dims, &cells);
        let meshes = material_meshes_mm(&grid, 2, 1e-3);
        for (m, mesh) in meshes.iter().enumerate() {
            let count = cells.iter().filter(|&&c| c == m as u8 + 1).count();
            if let Err(e) = assert_closed_manifold(mesh) {
                prop_assert!(false, "material {m}: {e}");
            }
            let volume = mesh.volume();
            prop_assert!(
                (volume - count as f64).abs() <= 1e-2 * (count as f64).max(1.0),
                "material {m}: volume {volume} mm³ for {count} voxels"
            );
        }
    }
}
