//! The isometric render: a known design gives a picture that is not blank, shows each material's
//! own colour (its top faces, unshaded), and encodes as a PNG of the stated size.

use amorph::material::{MaterialId, Palette};
use amorph::report::render_isometric;
use amorph::voxel::{GridDims, VoxelGrid};

#[test]
fn a_two_material_block_shows_both_colours_and_encodes_as_png() {
    let dims = GridDims::new(4, 3, 2);
    let cells = (0..24)
        .map(|i| Some(MaterialId(u8::from(i % 4 >= 2))))
        .collect();
    let grid = VoxelGrid::from_cells(dims, cells);
    let palette = Palette::hard_soft_resins();
    let image = render_isometric(&grid, &palette, 10.0);
    let background = image
        .pixels
        .iter()
        .filter(|&&p| p == [255, 255, 255])
        .count();
    assert!(background < image.pixels.len(), "blank render");
    for (_, m) in palette.iter() {
        let shown = image.pixels.iter().filter(|&&p| p == m.colour).count();
        // Each material has at least two top faces of 10 px sides: well over 50 pixels each.
        assert!(shown > 50, "{} shown on {shown} pixels", m.name);
    }
    let png = image.to_png().unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let width = u32::from_be_bytes(png[16..20].try_into().unwrap());
    let height = u32::from_be_bytes(png[20..24].try_into().unwrap());
    assert_eq!(
        (width as usize, height as usize),
        (image.width, image.height)
    );
}

#[test]
fn an_empty_design_renders_blank() {
    let grid = VoxelGrid::empty(GridDims::new(3, 3, 3));
    let image = render_isometric(&grid, &Palette::hard_soft_resins(), 8.0);
    assert!(image.pixels.iter().all(|&p| p == [255, 255, 255]));
}
