//! VXA (VoxCAD/Voxelyze) export: a written design reads back identical, the scene's settings are
//! in the file, and malformed files are refused with the element named.

use amorph::dynamics::foam_palette;
use amorph::export::{VxaDesign, read_vxa, write_voxcraft_base, write_vxa};
use amorph::material::{MaterialId, Palette};
use amorph::task::beam::{BeamScene, NamedProfile};
use amorph::task::locomotion::{LocomotionMetrics, LocomotionScene, Starts};
use amorph::task::{SimulatorSettings, Task};
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
    LocomotionScene::default().simulator_settings(GridDims::new(20, 20, 20), None)
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
    // Settling (at most 0.5 s), then ten cycles are measured; every voxel's phase offset puts the
    // reader's sine, counted from t = 0, at phase 0 when the settle ends, as ours starts.
    assert!((value("InitCmTime") - 0.5).abs() < 1e-12);
    assert!((value("StopConditionValue") - (0.5 + 10.0 * 0.07)).abs() < 1e-12);
    let offsets = phase_offsets(&doc);
    assert_eq!(offsets.len(), 2, "one per cell of the 2x1x1 grid");
    for phi in offsets {
        let cycles_at_start = value("InitCmTime") / value("TempPeriod") + phi;
        assert!(
            (cycles_at_start - cycles_at_start.round()).abs() < 1e-9,
            "the reader's sine starts at phase {cycles_at_start} cycles"
        );
    }
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
    // Its result's distance is unsigned; the centre-of-mass trace (20 samples a period, as our
    // trajectory.csv) carries the sign.
    assert_eq!(value("SaveTraces"), 1.0);
    assert!((value("TimeBetweenTraces") - 0.07 / 20.0).abs() < 1e-15);
}

/// A beam is written as its load case for the reader to relax: clamp and load regions that catch
/// exactly the root and tip layers under the reader's overlap rule, the whole tip load, no
/// gravity or floor, kinetic damping and a rest test set against the least strain energy.
#[test]
fn a_beam_is_written_as_its_clamped_and_loaded_layers() {
    let scene = BeamScene::new(NamedProfile::CircularArc);
    let dims = GridDims::new(6, 20, 6);
    let settings = scene
        .simulator_settings(dims, None)
        .expect("a beam has a load case");
    let d = design(&[2; 6 * 20 * 6], dims, Palette::hard_soft_resins());
    let text = write_vxa(&d, Some(&settings));
    let doc = roxmltree::Document::parse(&text).unwrap();
    let value = |node: roxmltree::Node<'_, '_>, name: &str| -> f64 {
        node.descendants()
            .find(|n| n.has_tag_name(name))
            .unwrap_or_else(|| panic!("<{name}> missing"))
            .text()
            .unwrap()
            .parse()
            .unwrap()
    };
    let root = doc.root_element();
    assert_eq!(value(root, "GravEnabled"), 0.0);
    assert_eq!(value(root, "FloorEnabled"), 0.0);
    assert_eq!(value(root, "TempEnabled"), 0.0);
    assert_eq!(value(root, "EquilibriumModeEnabled"), 1.0);
    assert_eq!(value(root, "StopConditionType"), 5.0);
    assert_eq!(value(root, "NumBCs"), 2.0);
    let regions: Vec<_> = root
        .descendants()
        .filter(|n| n.has_tag_name("FRegion"))
        .collect();
    assert_eq!(regions.len(), 2);
    // The reader's box test: a voxel (its cube, in workspace fractions) belongs to a region when
    // the open intervals overlap on every axis.
    let layers_caught = |r: roxmltree::Node<'_, '_>| -> Vec<usize> {
        let (y, dy) = (value(r, "Y"), value(r, "dY"));
        assert!(value(r, "X") <= 0.0 && value(r, "dX") >= 1.0);
        assert!(value(r, "Z") <= 0.0 && value(r, "dZ") >= 1.0);
        (0..dims.ny)
            .filter(|&l| {
                let (lo, hi) = (l as f64 / 20.0, (l + 1) as f64 / 20.0);
                hi > y && lo < y + dy
            })
            .collect()
    };
    assert_eq!(layers_caught(regions[0]), vec![0]);
    assert_eq!(value(regions[0], "DofFixed"), 63.0, "clamped in all six");
    assert_eq!(layers_caught(regions[1]), vec![19]);
    assert_eq!(value(regions[1], "DofFixed"), 0.0);
    assert_eq!(value(regions[1], "ForceZ"), -scene.tip_load);
    assert_eq!(
        value(regions[1], "ForceX") + value(regions[1], "ForceY"),
        0.0
    );
    // Rest: total kinetic energy below 1e-8 of the strain energy of the stiffest possible beam
    // (the reader stops when the energy per voxel stays below a thousandth of the value).
    let s = scene.length / 20.0;
    let (e, i) = (1e9, (6.0 * s) * (6.0 * s).powi(3) / 12.0);
    let least = 0.5 * scene.tip_load * scene.tip_load * scene.length.powi(3) / (3.0 * e * i);
    let per_voxel = 1e-3 * value(root, "StopConditionValue");
    let total = per_voxel * (6 * 20 * 6) as f64;
    assert!(
        (total / least - 1e-8).abs() < 1e-20,
        "{total} against {least}"
    );
}

/// Every `<PhaseOffset>` entry of a VXA, in cycles.
fn phase_offsets(doc: &roxmltree::Document) -> Vec<f64> {
    doc.descendants()
        .filter(|n| n.has_tag_name("PhaseOffset"))
        .flat_map(|n| n.children().filter(|c| c.has_tag_name("Layer")))
        .flat_map(|layer| {
            layer
                .text()
                .unwrap()
                .split(',')
                .map(|v| v.parse::<f64>().unwrap())
                .collect::<Vec<_>>()
        })
        .collect()
}

/// A robot's outcome as a file needs it: settled after 0.12 s, its gait, and its starts' gaits.
fn settled_at_0_12_s(gait: f64, start_fitness: Vec<f64>) -> LocomotionMetrics {
    LocomotionMetrics {
        displacement: 0.01,
        gait_displacement: gait,
        lateral: 0.0,
        speed_percent_per_cycle: 100.0 * gait / 0.02 / 10.0,
        body_length: 0.02,
        voxels: 2,
        material_counts: vec![1, 1],
        steps: 1000,
        dt: 1e-5,
        simulated_time: 0.82,
        settle_time: 0.12,
        centre_of_mass_trace: Vec::new(),
        start_fitness,
    }
}

/// With the design's outcome, the settle written is the one its evaluation measured (0.12 s),
/// and the phase offset starts the reader's sine there: 0.12 s is 1.714 periods of 0.07 s, so
/// the offset is 0.286 of a period; the reader starts actuating when ours did, in the same phase.
#[test]
fn a_robots_own_settle_is_written_when_its_outcome_is_known() {
    let scene = LocomotionScene::default();
    let metrics = settled_at_0_12_s(0.01, Vec::new());
    let dims = GridDims::new(20, 20, 20);
    let own = scene.simulator_settings(dims, Some(&metrics)).unwrap();
    let d = design(&[1, 2], GridDims::new(2, 1, 1), foam_palette());
    let text = write_vxa(&d, Some(&own));
    let number = |name: &str| -> f64 {
        let start = text.find(&format!("<{name}>")).unwrap() + name.len() + 2;
        text[start..].split('<').next().unwrap().parse().unwrap()
    };
    assert!((number("InitCmTime") - 0.12).abs() < 1e-12);
    assert!((number("StopConditionValue") - (0.12 + 0.7)).abs() < 1e-12);
    let doc = roxmltree::Document::parse(&text).unwrap();
    for phi in phase_offsets(&doc) {
        assert!((phi - (2.0 - 0.12 / 0.07)).abs() < 1e-12, "{phi}");
    }
    let bound = scene.simulator_settings(dims, None).unwrap();
    assert_eq!(bound.settle_time, scene.settle.max_time);
}

/// With several starts the file runs the scored (median) one: start 2 of three here, whose
/// actuation phase is two shifts of a period later, so the reader's offset grows by 2·shift.
#[test]
fn a_robot_with_several_starts_is_written_in_its_median_starts_phase() {
    let scene = LocomotionScene {
        starts: Starts {
            count: 3,
            shift: 0.01,
        },
        ..LocomotionScene::default()
    };
    let metrics = settled_at_0_12_s(0.004, vec![0.009, -0.002, 0.004]);
    let own = scene
        .simulator_settings(GridDims::new(20, 20, 20), Some(&metrics))
        .unwrap();
    let d = design(&[1, 2], GridDims::new(2, 1, 1), foam_palette());
    let doc_text = write_vxa(&d, Some(&own));
    let doc = roxmltree::Document::parse(&doc_text).unwrap();
    for phi in phase_offsets(&doc) {
        assert!((phi - (2.0 - 0.12 / 0.07 + 0.02)).abs() < 1e-12, "{phi}");
    }
}

#[test]
fn a_robot_has_no_regions_and_no_kinetic_damping() {
    let d = design(&[1, 2], GridDims::new(2, 1, 1), foam_palette());
    let text = write_vxa(&d, robot_settings().as_ref());
    assert!(text.contains("<NumBCs>0</NumBCs>"));
    assert!(text.contains("<EquilibriumModeEnabled>0</EquilibriumModeEnabled>"));
    assert!(!text.contains("<FRegion>"));
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

/// A robot's files hold the body as our simulation starts it: on the floor. Those readers drop a
/// body from where its grid puts it, so a design whose lowest voxels sit in layer 3 fell three
/// voxels there, tumbled and walked the other way (docs/how-to/voxelyze.md). Each voxel keeps its x
/// and y cell and its material; the empty layers below the body are gone, in the VXA and the VXD
/// alike.
#[test]
fn a_robot_is_written_resting_on_the_floor() {
    let dims = GridDims::new(4, 3, 6);
    let mut grid = VoxelGrid::empty(dims);
    // An L of two materials whose lowest voxel is in layer 3 and whose top is in layer 5.
    for (x, y, z, m) in [
        (1, 1, 3, 1),
        (2, 1, 3, 0),
        (2, 1, 4, 0),
        (2, 1, 5, 1),
        (3, 2, 4, 0),
    ] {
        grid.set(x, y, z, Some(MaterialId(m)));
    }
    let scene = amorph::task::Scene::Locomotion(LocomotionScene::default());
    let dir = std::env::temp_dir().join(format!("amorph-vxa-floor-{}", std::process::id()));
    amorph::export::write_fabrication_files(&dir, &grid, &scene, None).unwrap();
    let read = |name: &str| std::fs::read_to_string(dir.join(name)).unwrap();
    let vxa = read_vxa(&read("design.vxa")).unwrap().grid;
    let merged = read("voxcraft/design.vxd");
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(vxa.dims(), GridDims::new(4, 3, 3));
    assert_eq!(vxa.filled_count(), grid.filled_count());
    for z in 0..3 {
        for y in 0..3 {
            for x in 0..4 {
                assert_eq!(vxa.get(x, y, z), grid.get(x, y, z + 3), "cell {x} {y} {z}");
            }
        }
    }
    // The VXD's structure has the same three layers.
    assert!(merged.contains("<Z_Voxels>3</Z_Voxels>"), "{merged}");
    // A beam has no floor: its grid is written as it is, empty layers and all.
    let beam = amorph::task::Scene::Beam(BeamScene::new(NamedProfile::CircularArc));
    let beam_dir = std::env::temp_dir().join(format!("amorph-vxa-beam-{}", std::process::id()));
    let beam_grid = {
        let mut g = VoxelGrid::empty(GridDims::new(2, 6, 3));
        g.set(1, 0, 2, Some(MaterialId(0)));
        g
    };
    amorph::export::write_fabrication_files(&beam_dir, &beam_grid, &beam, None).unwrap();
    let back = read_vxa(&std::fs::read_to_string(beam_dir.join("design.vxa")).unwrap()).unwrap();
    std::fs::remove_dir_all(&beam_dir).unwrap();
    assert_eq!(back.grid, beam_grid);
}

/// Both readers (this VXA's and voxcraft-sim's base) damp the floor by ColDampingZ·2√(m·E·s)
/// whatever their floor spring; ours by 2ζ√(m·k) with k = `stiffness_factor`·E·s. The files must
/// carry our damping constant: ζ at our default spring, ζ·√factor at any other (writing ζ = 1/√2
/// unscaled at factor 2 would give a floor damped √2 less than ours).
#[test]
fn the_floor_is_damped_as_ours_whatever_our_floor_spring() {
    for (factor, zeta, expected) in [
        (1.0, 1.0, 1.0),
        (1.0, 0.3, 0.3),
        (2.0, std::f64::consts::FRAC_1_SQRT_2, 1.0),
        (4.0, 0.5, 1.0),
    ] {
        let mut settings = robot_settings().unwrap();
        settings.scene.damping.contact = zeta;
        settings.scene.floor.as_mut().unwrap().stiffness_factor = factor;
        let d = design(&[1, 2], GridDims::new(2, 1, 1), foam_palette());
        let texts = [
            write_vxa(&d, Some(&settings)),
            write_voxcraft_base(&d.palette, d.voxel_size, &settings),
        ];
        for text in texts {
            let doc = roxmltree::Document::parse(&text).unwrap();
            let z: f64 = doc
                .descendants()
                .find(|n| n.has_tag_name("ColDampingZ"))
                .and_then(|n| n.text())
                .unwrap()
                .parse()
                .unwrap();
            assert!(
                (z - expected).abs() < 1e-12,
                "factor {factor}, ζ {zeta}: ColDampingZ {z}"
            );
        }
    }
}
