//! VXA, the XML format of VoxCAD and Voxelyze (Hiller & Lipson's own tools): the design, its
//! materials and, for a dynamic scene, the simulation and environment settings, so an evolved robot
//! opens in VoxCAD and runs in Voxelyze.
//!
//! The settings are written the way the VoxCAD-era Voxelyze reader reads them (docs/exports.md,
//! measured with that reader built from `evosoro/_voxcad`): it actuates by thermal expansion, an
//! edge of s(1 + CTE·ΔT·sin(2πt/T)) with ΔT = `TempAmp` − `TempBase` (so both are written, 1 and
//! 0, with the newer `TempAmplitude` = 1 beside them); it lets no voxel grow past its rest size
//! unless `GrowthAmplitude` allows it; its only settle is `InitCmTime`, before which nothing
//! actuates and from which travel is measured, with the sine's phase counted from t = 0; and its
//! bond damping ratio is ours scaled by 2/√14 (its ratio refers to one bond, ours to the lattice's
//! top mode).

use std::fmt::Write;

use crate::dynamics::{DynamicScene, TOP_EIGENVALUE};
use crate::material::{Material, MaterialId, Palette};
use crate::task::SimulatorSettings;
use crate::voxel::{GridDims, VoxelGrid};

/// A design as VXA describes it.
#[derive(Clone, Debug, PartialEq)]
pub struct VxaDesign {
    pub grid: VoxelGrid,
    pub palette: Palette,
    /// Voxel edge length, m (`Lattice_Dim`).
    pub voxel_size: f64,
}

/// Why a VXA file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum VxaError {
    #[error("VXA is not well-formed XML: {0}")]
    Xml(#[from] roxmltree::Error),
    #[error("VXA element <{0}> is missing")]
    Missing(&'static str),
    #[error("VXA element <{element}> holds {value:?}, not a valid number")]
    Number {
        element: &'static str,
        value: String,
    },
    #[error("VXA layer {layer}: {message}")]
    Layer { layer: usize, message: String },
}

/// Writes a design as VXA. With a dynamic task's `settings`, its gravity, floor, damping,
/// time-step fraction and actuation go into the simulator and environment sections, with the
/// task's stop time (settling plus the actuation cycles).
pub fn write_vxa(design: &VxaDesign, settings: Option<&SimulatorSettings>) -> String {
    let mut x = String::new();
    let w = &mut x;
    // fmt::Write on a String cannot fail.
    let _ = writeln!(w, r#"<?xml version="1.0" encoding="ISO-8859-1"?>"#);
    let _ = writeln!(w, r#"<VXA Version="1.1">"#);
    if let Some(settings) = settings {
        write_simulator(w, settings);
        write_environment(w, &settings.scene);
    }
    let _ = writeln!(w, r#"<VXC Version="0.94">"#);
    let _ = writeln!(
        w,
        "<Lattice><Lattice_Dim>{}</Lattice_Dim><X_Dim_Adj>1</X_Dim_Adj><Y_Dim_Adj>1</Y_Dim_Adj><Z_Dim_Adj>1</Z_Dim_Adj><X_Line_Offset>0</X_Line_Offset><Y_Line_Offset>0</Y_Line_Offset><X_Layer_Offset>0</X_Layer_Offset><Y_Layer_Offset>0</Y_Layer_Offset></Lattice>",
        design.voxel_size
    );
    let _ = writeln!(
        w,
        "<Voxel><Vox_Name>BOX</Vox_Name><X_Squeeze>1</X_Squeeze><Y_Squeeze>1</Y_Squeeze><Z_Squeeze>1</Z_Squeeze></Voxel>"
    );
    let _ = writeln!(w, "<Palette>");
    let amplitude = settings
        .and_then(|s| s.scene.actuation.as_ref())
        .map_or(0.0, |a| edge_stroke(a.amplitude_volume));
    for (id, m) in design.palette.iter() {
        let cte = if m.actuated { amplitude } else { 0.0 };
        let [r, g, b] = m.colour.map(|c| f64::from(c) / 255.0);
        let _ = writeln!(
            w,
            "<Material ID=\"{}\"><MatType>0</MatType><Name>{}</Name><Display><Red>{r}</Red><Green>{g}</Green><Blue>{b}</Blue><Alpha>1</Alpha></Display><Mechanical><MatModel>0</MatModel><Elastic_Mod>{}</Elastic_Mod><Plastic_Mod>0</Plastic_Mod><Yield_Stress>0</Yield_Stress><FailModel>0</FailModel><Fail_Stress>0</Fail_Stress><Fail_Strain>0</Fail_Strain><Density>{}</Density><Poissons_Ratio>{}</Poissons_Ratio><CTE>{cte}</CTE><uStatic>{}</uStatic><uDynamic>{}</uDynamic><Actuated>{}</Actuated></Mechanical></Material>",
            id.index() + 1,
            super::xml_escape(&m.name),
            m.youngs_modulus,
            m.density,
            m.poisson_ratio,
            m.static_friction,
            m.kinetic_friction,
            u8::from(m.actuated),
        );
    }
    let _ = writeln!(w, "</Palette>");
    let d = design.grid.dims();
    let _ = writeln!(
        w,
        "<Structure Compression=\"ASCII_READABLE\"><X_Voxels>{}</X_Voxels><Y_Voxels>{}</Y_Voxels><Z_Voxels>{}</Z_Voxels><Data>",
        d.nx, d.ny, d.nz
    );
    for z in 0..d.nz {
        // One character per voxel, x fastest then y: '0' empty, else '0' + the 1-based material
        // ID (VoxCAD's ASCII_READABLE: '1'…'9', then ':' and up).
        let layer: String = (0..d.ny)
            .flat_map(|y| (0..d.nx).map(move |x| (x, y)))
            .map(|(x, y)| match design.grid.get(x, y, z) {
                None => '0',
                Some(m) => char::from(b'1'.saturating_add(m.0)),
            })
            .collect();
        let _ = writeln!(w, "<Layer><![CDATA[{layer}]]></Layer>");
    }
    let _ = writeln!(w, "</Data></Structure>");
    let _ = writeln!(w, "</VXC>");
    let _ = writeln!(w, "</VXA>");
    x
}

/// The reader's linear expansion per unit temperature that matches our volume sine's stroke: our
/// edge swings between (1 ± a)^(1/3) for a volume amplitude a, the reader's symmetrically by
/// ±CTE, so CTE is half the distance between the two (0.0672 for a = 0.2).
pub fn edge_stroke(amplitude_volume: f64) -> f64 {
    0.5 * ((1.0 + amplitude_volume).cbrt() - (1.0 - amplitude_volume).cbrt())
}

/// The reader's time-step fraction at most: at 1.0 its floor spring, which its step bound leaves
/// out, makes a resting body drift (5.6 mm in 0.7 s measured); 0.9 is its own default.
const READER_MAX_DT_FRACTION: f64 = 0.9;

fn write_simulator(w: &mut String, settings: &SimulatorSettings) {
    let scene = &settings.scene;
    let d = &scene.damping;
    // Settling ends on a whole period, so the reader's sine, whose phase runs from t = 0, starts
    // its first measured cycle at phase 0 as ours does.
    let (settle, stop) = match &scene.actuation {
        Some(a) => {
            let settle = (settings.settle_time / a.period).ceil() * a.period;
            (settle, settle + f64::from(settings.cycles) * a.period)
        }
        None => (settings.settle_time, settings.settle_time),
    };
    let _ = writeln!(
        w,
        "<Simulator><Integration><Integrator>0</Integrator><DtFrac>{}</DtFrac></Integration><Damping><BondDampingZ>{}</BondDampingZ><ColDampingZ>{}</ColDampingZ><SlowDampingZ>{}</SlowDampingZ></Damping><Collisions><SelfColEnabled>{}</SelfColEnabled><ColSystem>3</ColSystem><CollisionHorizon>3</CollisionHorizon></Collisions><Features><FluidDampEnabled>0</FluidDampEnabled><PoissonKickBackEnabled>0</PoissonKickBackEnabled><EnforceLatticeEnabled>0</EnforceLatticeEnabled></Features><StopCondition><StopConditionType>2</StopConditionType><StopConditionValue>{stop}</StopConditionValue><InitCmTime>{settle}</InitCmTime></StopCondition><GA><FitnessFileName>fitness.xml</FitnessFileName></GA></Simulator>",
        scene.dt_fraction.min(READER_MAX_DT_FRACTION),
        2.0 * d.link / TOP_EIGENVALUE.sqrt(),
        d.contact,
        d.global,
        u8::from(scene.collisions),
    );
}

fn write_environment(w: &mut String, scene: &DynamicScene) {
    let (temp_enabled, period, growth) = match &scene.actuation {
        Some(a) => (1, a.period, 2.0 * edge_stroke(a.amplitude_volume)),
        None => (0, 1.0, 0.0),
    };
    let _ = writeln!(
        w,
        "<Environment><Fixed_Regions><NumFixed>0</NumFixed></Fixed_Regions><Forced_Regions><NumForced>0</NumForced></Forced_Regions><Gravity><GravEnabled>{}</GravEnabled><GravAcc>{}</GravAcc><FloorEnabled>{}</FloorEnabled></Gravity><Thermal><TempEnabled>{temp_enabled}</TempEnabled><TempAmp>1</TempAmp><TempBase>0</TempBase><TempAmplitude>1</TempAmplitude><VaryTempEnabled>{temp_enabled}</VaryTempEnabled><TempPeriod>{period}</TempPeriod></Thermal><GrowthAmplitude>{growth}</GrowthAmplitude></Environment>",
        u8::from(scene.gravity > 0.0),
        -scene.gravity,
        u8::from(scene.floor.is_some()),
    );
}

/// Reads the design (lattice, palette, structure) of a VXA file.
pub fn read_vxa(text: &str) -> Result<VxaDesign, VxaError> {
    let doc = roxmltree::Document::parse(text)?;
    let root = doc.root_element();
    let voxel_size = number(root, "Lattice_Dim")?;
    let mut materials: Vec<(usize, Material)> = Vec::new();
    for node in find(root, "Palette")?
        .children()
        .filter(|n| n.has_tag_name("Material"))
    {
        let id: usize = node
            .attribute("ID")
            .and_then(|v| v.parse().ok())
            .ok_or(VxaError::Missing("Material ID"))?;
        let name = find(node, "Name")?.text().unwrap_or("").to_string();
        let mut m = Material::new(
            &name,
            number(node, "Elastic_Mod")?,
            number(node, "Poissons_Ratio")?,
        );
        m.density = number(node, "Density")?;
        m.static_friction = number(node, "uStatic")?;
        m.kinetic_friction = number(node, "uDynamic")?;
        m.actuated = number(node, "CTE")? != 0.0 || number(node, "Actuated").unwrap_or(0.0) != 0.0;
        let colour = |name| number(node, name).map(|v| (v * 255.0).round().clamp(0.0, 255.0) as u8);
        m.colour = [colour("Red")?, colour("Green")?, colour("Blue")?];
        materials.push((id, m));
    }
    materials.sort_by_key(|(id, _)| *id);
    let palette = Palette(materials.into_iter().map(|(_, m)| m).collect());

    let count = |name| number(root, name).map(|v| v as usize);
    let dims = GridDims::new(count("X_Voxels")?, count("Y_Voxels")?, count("Z_Voxels")?);
    let layers: Vec<&str> = find(root, "Data")?
        .children()
        .filter(|n| n.has_tag_name("Layer"))
        .map(|n| n.text().unwrap_or("").trim())
        .collect();
    if layers.len() != dims.nz {
        return Err(VxaError::Layer {
            layer: layers.len(),
            message: format!("{} layers for Z_Voxels = {}", layers.len(), dims.nz),
        });
    }
    let mut grid = VoxelGrid::empty(dims);
    for (z, layer) in layers.iter().enumerate() {
        let bytes = layer.as_bytes();
        if bytes.len() != dims.nx * dims.ny {
            return Err(VxaError::Layer {
                layer: z,
                message: format!("{} voxels, expected {}", bytes.len(), dims.nx * dims.ny),
            });
        }
        for (i, &c) in bytes.iter().enumerate() {
            let (x, y) = (i % dims.nx, i / dims.nx);
            let material = match c {
                b'0' => None,
                b'1'..=b'~' if usize::from(c - b'1') < palette.len() => Some(MaterialId(c - b'1')),
                _ => {
                    return Err(VxaError::Layer {
                        layer: z,
                        message: format!("voxel {i} is {:?}, not a palette ID", char::from(c)),
                    });
                }
            };
            grid.set(x, y, z, material);
        }
    }
    Ok(VxaDesign {
        grid,
        palette,
        voxel_size,
    })
}

fn find<'a, 'input>(
    parent: roxmltree::Node<'a, 'input>,
    name: &'static str,
) -> Result<roxmltree::Node<'a, 'input>, VxaError> {
    parent
        .descendants()
        .find(|n| n.has_tag_name(name))
        .ok_or(VxaError::Missing(name))
}

fn number(parent: roxmltree::Node<'_, '_>, name: &'static str) -> Result<f64, VxaError> {
    let text = find(parent, name)?.text().unwrap_or("").trim().to_string();
    text.parse().map_err(|_| VxaError::Number {
        element: name,
        value: text,
    })
}
