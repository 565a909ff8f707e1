//! The 3MF package: a valid OPC zip whose model holds one object per material present, each
//! pointing at its base material, with the same closed mesh (and volume) as the STL export.

use std::io::Read;

use amorph::export::{material_meshes_mm, write_3mf};
use amorph::material::{MaterialId, Palette};
use amorph::voxel::{GridDims, VoxelGrid};

#[test]
fn the_package_holds_one_object_per_material_with_its_mesh_and_volume() {
    let dims = GridDims::new(3, 4, 2);
    let cells: Vec<_> = (0..24)
        .map(|i| match i % 4 {
            0 => None,
            1 | 2 => Some(MaterialId(0)),
            _ => Some(MaterialId(1)),
        })
        .collect();
    let grid = VoxelGrid::from_cells(dims, cells);
    let palette = Palette::hard_soft_resins();
    let bytes = write_3mf(&grid, &palette, 2e-3).unwrap();
    let mut archive = zip::ZipArchive::new(std::io::Cursor::new(bytes)).unwrap();
    for part in ["[Content_Types].xml", "_rels/.rels"] {
        let mut text = String::new();
        archive
            .by_name(part)
            .unwrap()
            .read_to_string(&mut text)
            .unwrap();
        roxmltree::Document::parse(&text).expect(part);
    }
    let mut model = String::new();
    archive
        .by_name("3D/3dmodel.model")
        .unwrap()
        .read_to_string(&mut model)
        .unwrap();
    let doc = roxmltree::Document::parse(&model).unwrap();
    assert_eq!(doc.root_element().attribute("unit"), Some("millimeter"));
    let bases = doc.descendants().filter(|n| n.has_tag_name("base")).count();
    assert_eq!(bases, 2);
    let meshes = material_meshes_mm(&grid, 2, 2e-3);
    let counts = grid.material_counts(2);
    let objects: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("object"))
        .collect();
    assert_eq!(objects.len(), 2);
    for object in objects {
        let m: usize = object.attribute("pindex").unwrap().parse().unwrap();
        // Named after its material, so a slicer lists the bodies by material.
        assert_eq!(object.attribute("name"), Some(palette.0[m].name.as_str()));
        let vertices: Vec<[f64; 3]> = object
            .descendants()
            .filter(|n| n.has_tag_name("vertex"))
            .map(|v| ["x", "y", "z"].map(|a| v.attribute(a).unwrap().parse().unwrap()))
            .collect();
        let triangles: Vec<[u32; 3]> = object
            .descendants()
            .filter(|n| n.has_tag_name("triangle"))
            .map(|t| ["v1", "v2", "v3"].map(|a| t.attribute(a).unwrap().parse().unwrap()))
            .collect();
        // Coordinates are written with Rust's shortest round-trip formatting: exact.
        assert_eq!(vertices, meshes[m].vertices);
        assert_eq!(triangles, meshes[m].triangles);
        let expected = counts[m] as f64 * 8.0; // (2 mm)³ per voxel
        assert!((meshes[m].volume() - expected).abs() < 1e-2 * expected);
    }
    let items = doc.descendants().filter(|n| n.has_tag_name("item")).count();
    assert_eq!(items, 2);
}
