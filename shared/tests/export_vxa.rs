//! VXA (VoxCAD/Voxelyze) export: a written design reads back identical, the scene's settings are
//! in the file, and malformed files are refused with the element named.

use amorph::dynamics::foam_palette;
use amorph::export::{VxaDesign, read_vxa, write_vxa};
use amorph::material::{MaterialId, Palette};
use amorph::task::{SimulatorSettings, Task, locomotion::LocomotionScene};
use amorph::voxel::{GridDims, VoxelGrid};
use proptest::prelude::*;

fn design(cells: &[u8], dims: GridDims, palette: Palette) -> VxaDesign {
    VxaDesign {
        grid: VoxelGrid::from_cells(
            dims,
            cells
                .iter()
                .map(|&c| (c > 0).then(|| MaterialId(c - 1)))
                .collect(),
        ),
        palette,
        voxel_size: 1e-3,
    }
}

/// The paper's robot task at 20x20x20, as `worker export` writes it.
fn robot_settings() -> Option<SimulatorSettings> {
    LocomotionScene::default().simulator_settings(GridDims::new(20, 20, 20))
}

proptest! {
    /// Write then read gives the same grid, palette (every mechanical number bit for bit:
    /// Rust prints the shortest decimal that parses back to the same f64) and voxel size.
    #[test]
    fn vxa_round_trips_grid_palette_and_lattice(
        cells in prop::collection::vec(0u8..3, 3 * 4 * 5),
        size in 1e-5f64..1.0,
    ) {
        let mut d = design(&cells, GridDims::new(3, 4, 5), foam_palette());
        d.voxel_size = size;
        let text = write_vxa(&d, robot_settings().as_ref());
        let back = read_vxa(&text).unwrap();
        prop_assert_eq!(back, d);
    }
}

#[test]
fn the_scene_settings_are_written_for_voxelyze() {
    let d = design(&[1, 2], GridDims::new(2, 1, 1), foam_palette());
    let text = write_vxa(&d, robot_settings().as_ref());
    let doc = roxmltree::Document::parse(&text).unwrap();
    let value = |name: &str| -> f64 {
        doc.descendants()
            .find(|n| n.has_tag_name(name))
            .unwrap_or_else(|| panic!("<{name}> missing"))
            .text()
            .unwrap()
            .parse()
            .unwrap()
    };
    assert_eq!(value("GravAcc"), -9.81);
    assert_eq!(value("FloorEnabled"), 1.0);
    assert_eq!(value("TempPeriod"), 0.07);
    // The reader's swing is TempAmp − TempBase (the newer TempAmplitude beside it): one unit.
    assert_eq!(value("TempAmp") - value("TempBase"), 1.0);
    assert_eq!(value("TempAmplitude"), 1.0);
    // Its edge is s(1 + CTE sin): half the distance between our edge's extremes (1 ± 0.2)^(1/3)
    // for ±20 % volume, on the actuated foam only; voxels may grow by the whole stroke.
    let stroke = 0.5 * (1.2f64.cbrt() - 0.8f64.cbrt());
    let ctes: Vec<f64> = doc
        .descendants()
        .filter(|n| n.has_tag_name("CTE"))
        .map(|n| n.text().unwrap().parse().unwrap())
        .collect();
    assert_eq!(ctes.len(), 2);
    assert_eq!(ctes[0], 0.0);
    assert!((ctes[1] - stroke).abs() < 1e-15 && (ctes[1] - 0.0672).abs() < 1e-4);
    assert!(value("GrowthAmplitude") >= stroke);
    // Settling (at most 0.5 s) ends on a whole period (8 × 0.07 s), then ten cycles are measured.
    assert!((value("InitCmTime") - 0.56).abs() < 1e-12);
    assert!((value("StopConditionValue") - (0.56 + 10.0 * 0.07)).abs() < 1e-12);
    assert!(value("DtFrac") <= 0.9);
    // The reader's bond ratio refers to one bond, ours to the lattice's top mode (ω² = 14 k/m).
    let link = LocomotionScene::default()
        .dynamics_at(GridDims::new(20, 20, 20))
        .damping
        .link;
    assert!((value("BondDampingZ") - 2.0 * link / 14f64.sqrt()).abs() < 1e-15);
    let fitness_file = doc
        .descendants()
        .find(|n| n.has_tag_name("FitnessFileName"))
        .and_then(|n| n.text());
    assert_eq!(
        fitness_file,
        Some("fitness.xml"),
        "the reader writes a result only when named"
    );
}

#[test]
fn a_truncated_layer_is_refused_naming_the_layer() {
    let d = design(
        &[1, 0, 2, 1],
        GridDims::new(2, 2, 1),
        Palette::hard_soft_resins(),
    );
    let text = write_vxa(&d, None).replace("<![CDATA[1021]]>", "<![CDATA[102]]>");
    let err = read_vxa(&text).unwrap_err().to_string();
    assert!(err.contains("layer 0") && err.contains("3 voxels"), "{err}");
    let err = read_vxa("<VXA><VXC></VXC></VXA>").unwrap_err().to_string();
    assert!(err.contains("Lattice_Dim"), "{err}");
}
