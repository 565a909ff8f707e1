//! voxcraft-sim's pair of files: one `base.vxa` with the environment, the simulator settings and
//! the palette, shared by every design of a run, and one `.vxd` per design that replaces the
//! base's `<Structure>`. voxcraft-sim (the GPU successor of Voxelyze) merges each `.vxd` into the
//! base by the path in each child's `replace` attribute, then reads the result as a VXA.
//!
//! What its reader means, from its source (voxcraft/voxcraft-sim at dd8668f;
//! docs/how-to/voxelyze.md): the temperature is `TempAmplitude`·sin(2π(t/`TempPeriod` + phase)),
//! with no base temperature and no growth past rest size unless `<Simulator><EnableExpansion>` is
//! set; an edge is s(1 + CTE·T), linear as in the VoxCAD-era reader; a material's thermal expansion
//! can wait (`TurnOnThermalExpansionAfterThisManySeconds`) and the reference centre of mass can be
//! taken later (`ReinitializeInitialPositionAfterThisManySeconds`, read only with
//! `SecondaryExperiment`), which together are our settle; the stop condition and the fitness are
//! expression trees of `t` and of the centre of mass's offset (`x`, `y`, `z`). Poisson's ratio
//! enters its links only with `VolumeEffectsEnabled` (else ν = 0, shear modulus E/2), so it is
//! written as our coupling switch: our default (no coupling, ν in the shear modulus only) has no
//! exact counterpart there.

use std::fmt::Write;

use super::vxa::{
    READER_MAX_DT_FRACTION, bond_damping_z, collision_damping_z, edge_stroke, per_voxel_layers,
    whole_period_settle_and_stop, write_lattice, write_palette, write_structure,
};
use crate::material::Palette;
use crate::task::SimulatorSettings;
use crate::voxel::VoxelGrid;

/// The path voxcraft-sim puts a design's structure at.
const STRUCTURE_PATH: &str = "VXA.VXC.Structure";

/// `base.vxa`: everything but the design. The fitness is the centre of mass's travel along +x
/// (m) from the end of the settle to the stop, the closest the reader's fitness expression
/// comes to our steady-gait fitness (docs/how-to/voxelyze.md).
pub fn write_voxcraft_base(
    palette: &Palette,
    voxel_size: f64,
    settings: &SimulatorSettings,
) -> String {
    let scene = &settings.scene;
    let d = &scene.damping;
    let (settle, stop) = whole_period_settle_and_stop(settings);
    let (temp_enabled, period, stroke) = match &scene.actuation {
        Some(a) => (1, a.period, edge_stroke(a.amplitude_volume)),
        None => (0, 1.0, 0.0),
    };
    let mut x = String::new();
    let w = &mut x;
    // fmt::Write on a String cannot fail.
    let _ = writeln!(w, r#"<?xml version="1.0" encoding="ISO-8859-1"?>"#);
    let _ = writeln!(w, r#"<VXA Version="1.1">"#);
    let _ = writeln!(
        w,
        "<Simulator><Integration><Integrator>0</Integrator><DtFrac>{}</DtFrac></Integration><Damping><BondDampingZ>{}</BondDampingZ><ColDampingZ>{}</ColDampingZ><SlowDampingZ>{}</SlowDampingZ></Damping><AttachDetach><EnableCollision>{}</EnableCollision><EnableAttach>0</EnableAttach><EnableDetach>0</EnableDetach></AttachDetach><StopCondition><StopConditionFormula><mtSUB><mtVAR>t</mtVAR><mtCONST>{stop}</mtCONST></mtSUB></StopConditionFormula></StopCondition><RecordHistory><RecordStepSize>0</RecordStepSize><RecordVoxel>0</RecordVoxel><RecordLink>0</RecordLink></RecordHistory><FitnessFunction><mtVAR>x</mtVAR></FitnessFunction><Features><VolumeEffectsEnabled>{}</VolumeEffectsEnabled></Features><EnableExpansion>1</EnableExpansion><SecondaryExperiment>1</SecondaryExperiment><ReinitializeInitialPositionAfterThisManySeconds>{settle}</ReinitializeInitialPositionAfterThisManySeconds></Simulator>",
        scene.dt_fraction.min(READER_MAX_DT_FRACTION),
        bond_damping_z(d.link),
        collision_damping_z(scene),
        d.global,
        u8::from(scene.collisions),
        u8::from(scene.poisson),
    );
    let _ = writeln!(
        w,
        "<Environment><Gravity><GravEnabled>{}</GravEnabled><GravAcc>{}</GravAcc><FloorEnabled>{}</FloorEnabled></Gravity><Thermal><TempEnabled>{temp_enabled}</TempEnabled><TempBase>0</TempBase><TempAmplitude>1</TempAmplitude><VaryTempEnabled>{temp_enabled}</VaryTempEnabled><TempPeriod>{period}</TempPeriod></Thermal></Environment>",
        u8::from(scene.gravity > 0.0),
        -scene.gravity,
        u8::from(scene.floor.is_some()),
    );
    let _ = writeln!(w, r#"<VXC Version="0.94">"#);
    write_lattice(w, voxel_size);
    // Actuation waits for the settle; the reader's sine then starts at phase 0 (whole periods).
    write_palette(
        w,
        palette,
        stroke,
        &format!(
            "<TurnOnThermalExpansionAfterThisManySeconds>{settle}</TurnOnThermalExpansionAfterThisManySeconds>"
        ),
    );
    let _ = writeln!(w, "</VXC>");
    let _ = writeln!(w, "</VXA>");
    x
}

/// A design's `.vxd`: its structure, to replace the base's. Every voxel's actuation phase offset
/// and cilia forces are written (all zero: our actuation is in phase), because the reader's
/// import reads these per-voxel arrays whether or not the file has them, and without them it
/// reads uninitialised memory (found with its parser built for the CPU,
/// docs/how-to/voxelyze.md).
pub fn write_vxd(grid: &VoxelGrid) -> String {
    let d = grid.dims();
    let blocks = [
        per_voxel_layers("PhaseOffset", d, &[0.0]),
        per_voxel_layers("BaseCiliaForce", d, &[0.0; 3]),
        per_voxel_layers("ShiftCiliaForce", d, &[0.0; 3]),
    ]
    .concat();
    let mut x = String::new();
    let w = &mut x;
    let _ = writeln!(w, r#"<?xml version="1.0" encoding="ISO-8859-1"?>"#);
    let _ = writeln!(w, "<VXD>");
    write_structure(w, grid, &format!(" replace=\"{STRUCTURE_PATH}\""), &blocks);
    let _ = writeln!(w, "</VXD>");
    x
}
