//! VXA, the XML format of VoxCAD and Voxelyze (Hiller & Lipson's own tools): the design, its
//! materials and, for a dynamic scene, the simulation and environment settings, so an evolved robot
//! opens in VoxCAD and runs in Voxelyze.
//!
//! The settings are written the way the VoxCAD-era Voxelyze reader reads them
//! (docs/how-to/voxelyze.md, measured with that reader built from `evosoro/_voxcad`): it actuates
//! by thermal expansion, an edge of s(1 + CTE·ΔT·sin(2πt/T)) with ΔT = `TempAmp` − `TempBase` (so
//! both are written, 1 and 0, with the newer `TempAmplitude` = 1 beside them); it lets no voxel
//! grow past its rest size unless `GrowthAmplitude` allows it; its only settle is `InitCmTime`,
//! before which nothing actuates and from which travel is measured, with the sine's phase counted
//! from t = 0 (so every voxel gets the `PhaseOffset` that puts our phase at the settle's end); and
//! its bond damping ratio is ours scaled by 2/√14 (its ratio refers to one bond, ours to the
//! lattice's top mode).

use std::fmt::Write;

use crate::dynamics::{DynamicScene, TOP_EIGENVALUE};
use crate::material::{Material, MaterialId, Palette};
use crate::task::{LayerLoadCase, SimulatorSettings};
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
        write_simulator(w, settings, design.grid.filled_count());
        write_environment(w, settings, design.grid.dims().ny);
    }
    let _ = writeln!(w, r#"<VXC Version="0.94">"#);
    write_lattice(w, design.voxel_size);
    let stroke = settings
        .and_then(|s| s.scene.actuation.as_ref())
        .map_or(0.0, |a| edge_stroke(a.amplitude_volume));
    write_palette(w, &design.palette, stroke, "");
    let phases = settings
        .and_then(reader_phase_offset)
        .map_or(String::new(), |phase| {
            per_voxel_layers("PhaseOffset", design.grid.dims(), &[phase])
        });
    write_structure(w, &design.grid, "", &phases);
    let _ = writeln!(w, "</VXC>");
    let _ = writeln!(w, "</VXA>");
    x
}

/// `<Lattice>` and `<Voxel>`: cubic voxels of edge `voxel_size`, m.
pub(super) fn write_lattice(w: &mut String, voxel_size: f64) {
    let _ = writeln!(
        w,
        "<Lattice><Lattice_Dim>{voxel_size}</Lattice_Dim><X_Dim_Adj>1</X_Dim_Adj><Y_Dim_Adj>1</Y_Dim_Adj><Z_Dim_Adj>1</Z_Dim_Adj><X_Line_Offset>0</X_Line_Offset><Y_Line_Offset>0</Y_Line_Offset><X_Layer_Offset>0</X_Layer_Offset><Y_Layer_Offset>0</Y_Layer_Offset></Lattice>"
    );
    let _ = writeln!(
        w,
        "<Voxel><Vox_Name>BOX</Vox_Name><X_Squeeze>1</X_Squeeze><Y_Squeeze>1</Y_Squeeze><Z_Squeeze>1</Z_Squeeze></Voxel>"
    );
}

/// `<Palette>`, in ID order (readers of this family take the palette in file order and ignore
/// the `ID` attribute). An actuated material expands by `stroke` per unit of the temperature
/// swing; `actuated_extra` is appended to an actuated material's `<Mechanical>`.
pub(super) fn write_palette(w: &mut String, palette: &Palette, stroke: f64, actuated_extra: &str) {
    let _ = writeln!(w, "<Palette>");
    for (id, m) in palette.iter() {
        let (cte, extra) = if m.actuated {
            (stroke, actuated_extra)
        } else {
            (0.0, "")
        };
        let [r, g, b] = m.colour.map(|c| f64::from(c) / 255.0);
        let _ = writeln!(
            w,
            "<Material ID=\"{}\"><MatType>0</MatType><Name>{}</Name><Display><Red>{r}</Red><Green>{g}</Green><Blue>{b}</Blue><Alpha>1</Alpha></Display><Mechanical><MatModel>0</MatModel><Elastic_Mod>{}</Elastic_Mod><Plastic_Mod>0</Plastic_Mod><Yield_Stress>0</Yield_Stress><FailModel>0</FailModel><Fail_Stress>0</Fail_Stress><Fail_Strain>0</Fail_Strain><Density>{}</Density><Poissons_Ratio>{}</Poissons_Ratio><CTE>{cte}</CTE><uStatic>{}</uStatic><uDynamic>{}</uDynamic><Actuated>{}</Actuated>{extra}</Mechanical></Material>",
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
}

/// `<Structure>` as VoxCAD's ASCII_READABLE layers, bottom layer first; `attributes` go into the
/// opening tag after `Compression` (voxcraft's `replace`), `blocks` after the layers.
pub(super) fn write_structure(w: &mut String, grid: &VoxelGrid, attributes: &str, blocks: &str) {
    let d = grid.dims();
    let _ = writeln!(
        w,
        "<Structure Compression=\"ASCII_READABLE\"{attributes}><X_Voxels>{}</X_Voxels><Y_Voxels>{}</Y_Voxels><Z_Voxels>{}</Z_Voxels><Data>",
        d.nx, d.ny, d.nz
    );
    for z in 0..d.nz {
        // One character per voxel, x fastest then y: '0' empty, else '0' + the 1-based material
        // ID ('1'…'9', then ':' and up).
        let layer: String = (0..d.ny)
            .flat_map(|y| (0..d.nx).map(move |x| (x, y)))
            .map(|(x, y)| match grid.get(x, y, z) {
                None => '0',
                Some(m) => char::from(b'1'.saturating_add(m.0)),
            })
            .collect();
        let _ = writeln!(w, "<Layer><![CDATA[{layer}]]></Layer>");
    }
    let _ = writeln!(w, "</Data>{blocks}</Structure>");
}

/// The reader's linear expansion per unit temperature that matches our volume sine's stroke: our
/// edge swings between (1 ± a)^(1/3) for a volume amplitude a, the reader's symmetrically by
/// ±CTE, so CTE is half the distance between the two (0.0672 for a = 0.2).
pub fn edge_stroke(amplitude_volume: f64) -> f64 {
    0.5 * ((1.0 + amplitude_volume).cbrt() - (1.0 - amplitude_volume).cbrt())
}

/// The reader's time-step fraction at most: at 1.0 its floor spring, which its step bound leaves
/// out, makes a resting body drift (5.6 mm in 0.7 s measured); 0.9 is its own default.
pub(super) const READER_MAX_DT_FRACTION: f64 = 0.9;

/// `<name>` holding one `<Layer>` per z of `values` for every cell (x fastest, then y), the
/// layout these readers use for per-voxel arrays (they read the entries of filled cells only).
pub(super) fn per_voxel_layers(name: &str, dims: GridDims, values: &[f64]) -> String {
    let cell = values
        .iter()
        .map(f64::to_string)
        .collect::<Vec<_>>()
        .join(",");
    let layer = vec![cell.as_str(); dims.nx * dims.ny].join(",");
    let mut block = format!("<{name}>");
    for _ in 0..dims.nz {
        let _ = write!(block, "<Layer><![CDATA[{layer}]]></Layer>");
    }
    let _ = write!(block, "</{name}>");
    block
}

/// The reader's phase offset, in periods, that makes its sin(2π(t/T + φ)) our
/// sin(2π(t − t_settle)/T + phase) once actuation starts at `InitCmTime` = t_settle; in [0, 1).
/// `None` without actuation or for a load case.
pub(super) fn reader_phase_offset(settings: &SimulatorSettings) -> Option<f64> {
    let a = settings.scene.actuation.as_ref()?;
    if settings.load_case.is_some() {
        return None;
    }
    Some((a.phase / std::f64::consts::TAU - settings.settle_time / a.period).rem_euclid(1.0))
}

/// When the reader starts actuating and measuring, and when it stops, s: the settle exactly as
/// written (the phase offset carries the sine's start), then the task's cycles.
fn settle_and_stop(settings: &SimulatorSettings) -> (f64, f64) {
    match &settings.scene.actuation {
        Some(a) => (
            settings.settle_time,
            settings.settle_time + f64::from(settings.cycles) * a.period,
        ),
        None => (settings.settle_time, settings.settle_time),
    }
}

/// The same for readers given no per-design phase (voxcraft-sim's base, shared by every design):
/// the settle is rounded up to a whole period, so the first measured cycle starts at phase 0 as
/// ours does, and the stop is the task's cycles after it.
pub(super) fn whole_period_settle_and_stop(settings: &SimulatorSettings) -> (f64, f64) {
    match &settings.scene.actuation {
        Some(a) => {
            let settle = (settings.settle_time / a.period).ceil() * a.period;
            (settle, settle + f64::from(settings.cycles) * a.period)
        }
        None => (settings.settle_time, settings.settle_time),
    }
}

/// The reader's bond damping ratio for our link damping ratio. Readers of this family damp a link
/// by ζ_v·√(m·k) per unit of relative velocity (2√m·ζ_v/dt on half a step's relative motion); ours
/// is β·k = 2ζ·√(m·k)/√14, ζ being the ratio at the lattice's top mode (`TOP_EIGENVALUE`).
pub(super) fn bond_damping_z(link: f64) -> f64 {
    2.0 * link / TOP_EIGENVALUE.sqrt()
}

/// The reader's collision damping ratio for our floor contact. Readers of this family damp the
/// floor by ζ_v·2√(m·E·s) whatever their floor spring (2·E·s); ours by 2ζ·√(m·k) with our spring
/// k = `stiffness_factor`·E·s. So the same damping constant is ζ·√`stiffness_factor` there (ζ itself
/// at our default factor 1). Voxel-to-voxel collisions use the same ratio in those readers.
pub(super) fn collision_damping_z(scene: &DynamicScene) -> f64 {
    let factor = scene.floor.as_ref().map_or(1.0, |f| f.stiffness_factor);
    scene.damping.contact * factor.sqrt()
}

/// Kinetic energy, as a part of the least strain energy the load case stores, below which the
/// reader's relaxation counts as rest: the displacement left is then about √ of it (1e-4).
const REST_ENERGY_FRACTION: f64 = 1e-8;

fn write_simulator(w: &mut String, settings: &SimulatorSettings, voxels: usize) {
    let scene = &settings.scene;
    let d = &scene.damping;
    let (settle, stop) = settle_and_stop(settings);
    // A load case relaxes with the reader's kinetic damping (every velocity zeroed at each peak of
    // kinetic energy) until its kinetic energy stays below the rest level (stop type 5: per voxel
    // below a thousandth of the value); a robot runs for its time.
    let (stop_type, stop_value, equilibrium) = match &settings.load_case {
        Some(case) => (
            5,
            1e3 * REST_ENERGY_FRACTION * case.min_strain_energy / voxels.max(1) as f64,
            1,
        ),
        None => (2, stop, 0),
    };
    let _ = writeln!(
        w,
        "<Simulator><Integration><Integrator>0</Integrator><DtFrac>{}</DtFrac></Integration><Damping><BondDampingZ>{}</BondDampingZ><ColDampingZ>{}</ColDampingZ><SlowDampingZ>{}</SlowDampingZ></Damping><Collisions><SelfColEnabled>{}</SelfColEnabled><ColSystem>3</ColSystem><CollisionHorizon>3</CollisionHorizon></Collisions><Features><FluidDampEnabled>0</FluidDampEnabled><PoissonKickBackEnabled>0</PoissonKickBackEnabled><EnforceLatticeEnabled>0</EnforceLatticeEnabled></Features><StopCondition><StopConditionType>{stop_type}</StopConditionType><StopConditionValue>{stop_value:e}</StopConditionValue><InitCmTime>{settle}</InitCmTime></StopCondition><EquilibriumMode><EquilibriumModeEnabled>{equilibrium}</EquilibriumModeEnabled></EquilibriumMode><GA><FitnessFileName>fitness.xml</FitnessFileName></GA></Simulator>",
        scene.dt_fraction.min(READER_MAX_DT_FRACTION),
        bond_damping_z(d.link),
        collision_damping_z(scene),
        d.global,
        u8::from(scene.collisions),
    );
}

fn write_environment(w: &mut String, settings: &SimulatorSettings, ny: usize) {
    let scene = &settings.scene;
    let (temp_enabled, period, growth) = match &scene.actuation {
        Some(a) => (1, a.period, 2.0 * edge_stroke(a.amplitude_volume)),
        None => (0, 1.0, 0.0),
    };
    // A robot's centre-of-mass trace in the reader's result file, sampled as our trajectory.csv is
    // (20 a period): its own result is an unsigned distance, the trace gives the travel's sign.
    let traces = match (&scene.actuation, &settings.load_case) {
        (Some(a), None) => format!(
            "<SaveTraces>1</SaveTraces><TimeBetweenTraces>{}</TimeBetweenTraces>",
            a.period / 20.0
        ),
        _ => String::new(),
    };
    let _ = write!(w, "<Environment>");
    write_boundary_conditions(w, settings.load_case.as_ref(), ny);
    let _ = writeln!(
        w,
        "<Gravity><GravEnabled>{}</GravEnabled><GravAcc>{}</GravAcc><FloorEnabled>{}</FloorEnabled></Gravity><Thermal><TempEnabled>{temp_enabled}</TempEnabled><TempAmp>1</TempAmp><TempBase>0</TempBase><TempAmplitude>1</TempAmplitude><VaryTempEnabled>{temp_enabled}</VaryTempEnabled><TempPeriod>{period}</TempPeriod></Thermal><GrowthAmplitude>{growth}</GrowthAmplitude>{traces}</Environment>",
        u8::from(scene.gravity > 0.0),
        -scene.gravity,
        u8::from(scene.floor.is_some()),
    );
}

/// The clamp and the tip load as two box regions in the reader's workspace fractions. A voxel
/// belongs to a region when its cube overlaps the box, so each box is the middle half of its
/// layer (a box flush with the layer's faces would also catch the next layer wherever rounding
/// lets the faces overlap). The reader shares a region's force equally among its voxels, as we do.
fn write_boundary_conditions(w: &mut String, case: Option<&LayerLoadCase>, ny: usize) {
    let Some(case) = case else {
        let _ = write!(
            w,
            "<Boundary_Conditions><NumBCs>0</NumBCs></Boundary_Conditions>"
        );
        return;
    };
    let layer = 1.0 / ny as f64;
    let region = |y: f64, dof_fixed: u8, force: [f64; 3]| {
        format!(
            "<FRegion><PrimType>0</PrimType><X>0</X><Y>{}</Y><Z>0</Z><dX>1</dX><dY>{}</dY><dZ>1</dZ><Radius>0</Radius><R>0.5</R><G>0.5</G><B>0.5</B><alpha>1</alpha><DofFixed>{dof_fixed}</DofFixed><ForceX>{}</ForceX><ForceY>{}</ForceY><ForceZ>{}</ForceZ><TorqueX>0</TorqueX><TorqueY>0</TorqueY><TorqueZ>0</TorqueZ><DisplaceX>0</DisplaceX><DisplaceY>0</DisplaceY><DisplaceZ>0</DisplaceZ><AngDisplaceX>0</AngDisplaceX><AngDisplaceY>0</AngDisplaceY><AngDisplaceZ>0</AngDisplaceZ></FRegion>",
            y + 0.25 * layer,
            0.5 * layer,
            force[0],
            force[1],
            force[2]
        )
    };
    let _ = write!(
        w,
        "<Boundary_Conditions><NumBCs>2</NumBCs>{}{}</Boundary_Conditions>",
        region(0.0, ALL_DEGREES_OF_FREEDOM, [0.0; 3]),
        region((ny - 1) as f64 * layer, 0, case.tip_force),
    );
}

/// The reader's bit mask of fixed degrees of freedom: x, y, z, and the three rotations.
const ALL_DEGREES_OF_FREEDOM: u8 = 63;

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
