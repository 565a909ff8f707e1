//! voxcraft-sim's pair (`base.vxa` + one `.vxd` per design): merged the way voxcraft-sim merges
//! them (each VXD child put at the path its `replace` attribute names), the pair is the design we
//! wrote, and every setting voxcraft-sim reads holds the value our protocol means.

use amorph::dynamics::foam_palette;
use amorph::export::{VxaDesign, read_vxa, write_voxcraft_base, write_vxd};
use amorph::material::{MaterialId, Palette};
use amorph::task::{SimulatorSettings, Task, locomotion::LocomotionScene};
use amorph::voxel::{GridDims, VoxelGrid};
use proptest::prelude::*;

fn grid(cells: &[u8], dims: GridDims) -> VoxelGrid {
    VoxelGrid::from_cells(
        dims,
        cells
            .iter()
            .map(|&c| (c > 0).then(|| MaterialId(c - 1)))
            .collect(),
    )
}

fn robot_settings() -> SimulatorSettings {
    LocomotionScene::default()
        .simulator_settings(GridDims::new(20, 20, 20), None)
        .expect("a robot has dynamics settings")
}

/// voxcraft-sim's merge (boost property-tree `put_child` at the `replace` path) for the paths our
/// VXD uses: the path must be `VXA.VXC.<child>`, and the child replaces the base's element of that
/// name or, when the base has none, is appended to `<VXC>`.
fn merge(base: &str, vxd: &str) -> String {
    let doc = roxmltree::Document::parse(vxd).expect("VXD is XML");
    assert!(doc.root_element().has_tag_name("VXD"));
    let mut merged = base.to_string();
    for child in doc.root_element().children().filter(|n| n.is_element()) {
        let path = child
            .attribute("replace")
            .expect("every VXD child names its path");
        let name = path
            .strip_prefix("VXA.VXC.")
            .expect("a path into the VXC section");
        assert_eq!(
            child.tag_name().name(),
            name,
            "the child is what it replaces"
        );
        let text = &vxd[child.range()];
        let open = format!("<{name}");
        match merged.find(&open) {
            Some(start) => {
                let close = format!("</{name}>");
                let end = merged[start..].find(&close).expect("closed") + start + close.len();
                merged.replace_range(start..end, text);
            }
            None => {
                let at = merged.find("</VXC>").expect("the base has a VXC section");
                merged.insert_str(at, text);
            }
        }
    }
    merged
}

fn values(text: &str, name: &str) -> Vec<f64> {
    roxmltree::Document::parse(text)
        .expect("XML")
        .descendants()
        .filter(|n| n.has_tag_name(name))
        .map(|n| n.text().unwrap_or("").trim().parse().expect("a number"))
        .collect()
}

fn value(text: &str, name: &str) -> f64 {
    let v = values(text, name);
    assert_eq!(v.len(), 1, "exactly one <{name}>");
    v[0]
}

proptest! {
    /// Base and VXD merged as voxcraft-sim merges them read back as the design: grid, palette
    /// and voxel size, whatever the design.
    #[test]
    fn the_merged_pair_is_the_design(
        cells in prop::collection::vec(0u8..3, 4 * 3 * 5),
        size in 1e-5f64..1.0,
    ) {
        let palette: Palette = foam_palette();
        let g = grid(&cells, GridDims::new(4, 3, 5));
        let merged = merge(&write_voxcraft_base(&palette, size, &robot_settings()), &write_vxd(&g));
        let back = read_vxa(&merged).unwrap();
        prop_assert_eq!(back, VxaDesign { grid: g, palette, voxel_size: size });
    }
}

/// One base serves every design: it holds no structure, and a second design merged into the same
/// base replaces nothing of the first's settings.
#[test]
fn the_base_holds_no_design_and_serves_many() {
    let base = write_voxcraft_base(&foam_palette(), 1e-3, &robot_settings());
    assert!(!base.contains("<Structure"));
    let a = merge(&base, &write_vxd(&grid(&[1, 2], GridDims::new(2, 1, 1))));
    let b = merge(&base, &write_vxd(&grid(&[2, 0, 1], GridDims::new(1, 1, 3))));
    let without_structure = |t: &str| {
        let (s, e) = (
            t.find("<Structure").unwrap(),
            t.find("</Structure>").unwrap(),
        );
        format!("{}{}", &t[..s], &t[e..])
    };
    assert_eq!(without_structure(&a), without_structure(&b));
    assert_eq!(read_vxa(&b).unwrap().grid.dims(), GridDims::new(1, 1, 3));
}

#[test]
fn the_settings_are_written_with_voxcraft_sims_meaning() {
    let settings = robot_settings();
    let base = write_voxcraft_base(&foam_palette(), 1e-3, &settings);
    assert_eq!(value(&base, "GravAcc"), -9.81);
    assert_eq!(value(&base, "FloorEnabled"), 1.0);
    assert_eq!(value(&base, "TempPeriod"), 0.07);
    // Its temperature is TempAmplitude·sin(2πt/T) with no base, and it grows voxels past their
    // rest size only with EnableExpansion.
    assert_eq!(value(&base, "TempAmplitude"), 1.0);
    assert_eq!(value(&base, "EnableExpansion"), 1.0);
    // An edge of s(1 + CTE·T): half the distance between our edge's extremes for ±20 % volume,
    // on the actuated foam only.
    let ctes = values(&base, "CTE");
    assert_eq!(ctes, vec![0.0, 0.5 * (1.2f64.cbrt() - 0.8f64.cbrt())]);
    // The settle (at most 0.5 s) on a whole period, 8 × 0.07 s: the actuated material waits for
    // it, the reference centre of mass is taken then (read only in a secondary experiment), and
    // the run stops ten periods later (the stop condition t − 1.26 > 0).
    let waits = values(&base, "TurnOnThermalExpansionAfterThisManySeconds");
    assert_eq!(waits.len(), 1, "only the actuated material waits");
    assert!((waits[0] - 0.56).abs() < 1e-12);
    assert!((value(&base, "ReinitializeInitialPositionAfterThisManySeconds") - 0.56).abs() < 1e-12);
    assert_eq!(value(&base, "SecondaryExperiment"), 1.0);
    let doc = roxmltree::Document::parse(&base).unwrap();
    let formula = doc
        .descendants()
        .find(|n| n.has_tag_name("StopConditionFormula"))
        .expect("a stop condition");
    let sub = formula.first_element_child().expect("an expression");
    assert!(sub.has_tag_name("mtSUB"));
    let operands: Vec<(&str, &str)> = sub
        .children()
        .filter(|n| n.is_element())
        .map(|n| (n.tag_name().name(), n.text().unwrap().trim()))
        .collect();
    assert_eq!(operands[0], ("mtVAR", "t"));
    assert_eq!(operands[1].0, "mtCONST");
    let stop: f64 = operands[1].1.parse().unwrap();
    assert!((stop - (0.56 + 10.0 * 0.07)).abs() < 1e-12);
    // The fitness is the centre of mass's offset along x from that reference.
    let fitness = doc
        .descendants()
        .find(|n| n.has_tag_name("FitnessFunction"))
        .and_then(|n| n.first_element_child())
        .expect("a fitness expression");
    assert_eq!(
        (fitness.tag_name().name(), fitness.text()),
        ("mtVAR", Some("x"))
    );
    // Poisson's ratio reaches its links only with volume effects, our coupling switch (off).
    assert_eq!(value(&base, "VolumeEffectsEnabled"), 0.0);
    // The time step and the link damping as the VoxCAD-era reader takes them (same link model).
    assert!(value(&base, "DtFrac") <= 0.9);
    let link = settings.scene.damping.link;
    assert!((value(&base, "BondDampingZ") - 2.0 * link / 14f64.sqrt()).abs() < 1e-15);
}

#[test]
fn a_vxd_replaces_only_the_structure() {
    let vxd = write_vxd(&grid(&[1, 0, 2, 2], GridDims::new(2, 2, 1)));
    let doc = roxmltree::Document::parse(&vxd).unwrap();
    let children: Vec<_> = doc
        .root_element()
        .children()
        .filter(|n| n.is_element())
        .collect();
    assert_eq!(children.len(), 1);
    assert_eq!(children[0].attribute("replace"), Some("VXA.VXC.Structure"));
    assert_eq!(children[0].attribute("Compression"), Some("ASCII_READABLE"));
}

/// The reader's import fills every voxel's phase offset and cilia forces from these blocks; a
/// VXD without them leaves it reading uninitialised memory. One value per voxel per layer for the
/// phase, three for each force, all zero (our actuation is in phase and has no cilia).
#[test]
fn every_voxel_has_a_phase_offset_and_cilia_forces() {
    let dims = GridDims::new(3, 2, 4);
    let vxd = write_vxd(&grid(&[1; 3 * 2 * 4], dims));
    let doc = roxmltree::Document::parse(&vxd).unwrap();
    for (block, per_voxel) in [
        ("PhaseOffset", 1),
        ("BaseCiliaForce", 3),
        ("ShiftCiliaForce", 3),
    ] {
        let node = doc
            .descendants()
            .find(|n| n.has_tag_name(block))
            .unwrap_or_else(|| panic!("<{block}> missing"));
        let layers: Vec<&str> = node
            .children()
            .filter(|n| n.has_tag_name("Layer"))
            .map(|n| n.text().unwrap())
            .collect();
        assert_eq!(layers.len(), dims.nz, "{block}");
        for layer in layers {
            let values: Vec<f64> = layer.split(',').map(|v| v.parse().unwrap()).collect();
            assert_eq!(values.len(), dims.nx * dims.ny * per_voxel, "{block}");
            assert!(values.iter().all(|&v| v == 0.0));
        }
    }
}
