//! What a locomotion run reports: the Table IV quantities beside the paper's simulated robot, the
//! best robot walking (animation and centre-of-mass path), and the bounds an outcome from a peer
//! must respect.

use std::path::Path;

use super::animation::{AnimationOptions, write_locomotion_animation};
use super::recording::RecordingOptions;
use super::scene::{LocomotionMetrics, LocomotionScene};
use super::starts::Starts;
use super::trajectory::{trajectory_csv, trajectory_plot};
use crate::genome::Genome;
use crate::report::Block;
use crate::task::Artefact;
use crate::task::error::{ImplausibleClaim, counts_fit, implausible};
use crate::voxel::GridDims;

/// The paper's simulated robot's speed, % of body length per actuation cycle (Table IV).
pub const PAPER_SPEED_PERCENT_PER_CYCLE: f64 = 3.38;

pub(super) fn summary(scene: &LocomotionScene, m: Option<&LocomotionMetrics>) -> serde_json::Value {
    serde_json::json!({
        "task": "locomotion",
        "heading_degrees": scene.heading_degrees,
        "incline_degrees": scene.incline_degrees,
        "displacement_m": m.map(|m| m.displacement),
        "gait_displacement_m": m.map(|m| m.gait_displacement),
        "lateral_m": m.map(|m| m.lateral),
        "speed_percent_body_length_per_cycle": m.map(|m| m.speed_percent_per_cycle),
        "paper_speed_percent_body_length_per_cycle": PAPER_SPEED_PERCENT_PER_CYCLE,
        "body_length_m": m.map(|m| m.body_length),
        "voxels": m.map(|m| m.voxels),
        "material_counts": m.map(|m| m.material_counts.clone()),
        "centre_of_mass_trace": m.map(|m| m.centre_of_mass_trace.clone()),
        "starts": scene.starts.count,
        "start_fitness_m": m.map(|m| m.start_fitness.clone()),
    })
}

/// Table IV's quantities for the best robot beside the paper's simulated robot (18 mm, 1.675 g,
/// printed as 1.675×10⁻³ (kg), 0.07 s period, 3.38 % of body length per cycle).
pub(super) fn table(
    scene: &LocomotionScene,
    m: Option<&LocomotionMetrics>,
    dims: GridDims,
) -> (String, Block) {
    let s = scene.dynamics_at(dims).voxel_size;
    let mass_mg = m.map(|m| {
        let kg: f64 = m
            .material_counts
            .iter()
            .zip(&scene.palette.0)
            .map(|(&n, material)| n as f64 * material.density * s.powi(3))
            .sum();
        1e6 * kg
    });
    let period = scene.dynamics.actuation.as_ref().map(|a| a.period);
    let num = |v: Option<f64>, digits: usize, unit: &str| {
        v.map_or("-".to_string(), |v| format!("{v:.digits$}{unit}"))
    };
    let row =
        |name: &str, ours: String, paper: &str| vec![name.to_string(), ours, paper.to_string()];
    let paper_speed = format!("{PAPER_SPEED_PERCENT_PER_CYCLE} %");
    let mut rows = vec![
        row(
            "body length",
            num(m.map(|m| 1e3 * m.body_length), 2, " mm"),
            "18 mm",
        ),
        row(
            "voxels",
            m.map_or("-".into(), |m| format!("{} at {dims}", m.voxels)),
            "20x20x20 workspace",
        ),
        row(
            "mass",
            num(mass_mg, 3, " mg"),
            "1,675 mg (Table IV: 1.675×10⁻³, read as kg)",
        ),
        row("actuation period", num(period, 3, " s"), "0.07 s"),
        row("actuation cycles", scene.actuation_cycles.to_string(), "-"),
    ];
    if scene.heading_degrees != 0.0 || scene.incline_degrees != 0.0 {
        rows.push(row(
            "heading, incline",
            format!("{}°, {}°", scene.heading_degrees, scene.incline_degrees),
            "0°, 0°",
        ));
    }
    rows.push(row(
        "gait travel (fitness: median cycle × cycles)",
        num(m.map(|m| 1e3 * m.gait_displacement), 3, " mm"),
        "-",
    ));
    if scene.starts.count > 1 {
        let spread = m.map_or("-".into(), |m| {
            let mm: Vec<String> = m
                .start_fitness
                .iter()
                .map(|f| format!("{:.3}", 1e3 * f))
                .collect();
            format!("{} mm (median scored)", mm.join(", "))
        });
        rows.push(row(
            &format!(
                "gait of each start ({} starts, {} period apart)",
                scene.starts.count, scene.starts.shift
            ),
            spread,
            "one start",
        ));
    }
    rows.extend([
        row(
            "total travel of the centre of mass",
            num(m.map(|m| 1e3 * m.displacement), 3, " mm"),
            "-",
        ),
        row(
            "drift across the heading",
            num(m.map(|m| 1e3 * m.lateral), 3, " mm"),
            "-",
        ),
        row(
            "speed (% body length per cycle)",
            num(m.map(|m| m.speed_percent_per_cycle), 3, " %"),
            &paper_speed,
        ),
    ]);
    (
        "Locomotion speed (paper Table IV)".into(),
        Block::Table {
            header: ["", "this run (simulated)", "paper (simulated)"]
                .map(String::from)
                .to_vec(),
            rows,
        },
    )
}

/// animation.gif (the robot moving), trajectory.png (its centre of mass against time and seen
/// from above) and trajectory.csv (the samples), from one more simulation of the robot.
pub(super) fn write_pictures(
    scene: &LocomotionScene,
    dir: &Path,
    genome: &Genome,
    dims: GridDims,
) -> std::io::Result<Vec<Artefact>> {
    let mut gif = Vec::new();
    let recording = write_locomotion_animation(
        genome,
        scene,
        dims,
        RecordingOptions::default(),
        AnimationOptions::default(),
        &mut gif,
    )
    .map_err(std::io::Error::other)?;
    std::fs::write(dir.join("animation.gif"), gif)?;
    let png = trajectory_plot(&recording)
        .to_png()
        .map_err(std::io::Error::other)?;
    std::fs::write(dir.join("trajectory.png"), png)?;
    std::fs::write(dir.join("trajectory.csv"), trajectory_csv(&recording))?;
    let picture = |path: &str, caption: &str| Artefact {
        path: path.into(),
        caption: Some(caption.into()),
    };
    Ok(vec![
        picture("animation.gif", "the best robot walking (10x slow motion)"),
        picture(
            "trajectory.png",
            "centre of mass: x against time, and the path seen from above",
        ),
        Artefact {
            path: "trajectory.csv".into(),
            caption: None,
        },
    ])
}

/// The bounds of a robot's outcome at `dims`. The travel figures are recomputed from the
/// centre-of-mass trace exactly as the evaluation computes them, so they must agree to the bit;
/// no voxel may move more than the divergence limit per step, so the trace cannot leave the
/// reach of `steps` such steps; counts fit the grid.
pub(super) fn check_metrics(
    scene: &LocomotionScene,
    fitness: f64,
    m: &LocomotionMetrics,
    dims: GridDims,
) -> Result<(), ImplausibleClaim> {
    counts_fit(m.voxels, &m.material_counts, scene.palette.len(), dims)?;
    let dynamics = scene.dynamics_at(dims);
    let s = dynamics.voxel_size;
    let positive = |name: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(implausible!("{name} = {v} must be positive"))
        }
    };
    positive("dt", m.dt)?;
    positive("simulated_time", m.simulated_time)?;
    if !(m.settle_time.is_finite() && (0.0..=m.simulated_time).contains(&m.settle_time)) {
        return Err(implausible!(
            "settle_time = {} outside the simulated time",
            m.settle_time
        ));
    }
    if m.steps == 0
        || !((m.steps as f64 * m.dt) - m.simulated_time)
            .abs()
            .le(&(1e-6 * m.simulated_time))
    {
        return Err(implausible!(
            "steps = {} at dt = {} do not make simulated_time = {}",
            m.steps,
            m.dt,
            m.simulated_time
        ));
    }
    let longest = dims.nx.max(dims.ny).max(dims.nz) as f64 * s;
    if !(m.body_length > 0.0 && m.body_length <= longest * 2f64.sqrt() + s) {
        return Err(implausible!(
            "body_length = {} m does not fit the workspace",
            m.body_length
        ));
    }
    let trace = &m.centre_of_mass_trace;
    if trace.len() != scene.actuation_cycles as usize + 1 {
        return Err(implausible!(
            "centre_of_mass_trace has {} points, expected {} (settled, then each cycle)",
            trace.len(),
            scene.actuation_cycles + 1
        ));
    }
    let reach = dynamics.divergence.max_step_travel * s * m.steps as f64 + longest;
    for (i, c) in trace.iter().enumerate() {
        if c.iter().any(|v| !(v.is_finite() && v.abs() <= reach)) {
            return Err(implausible!(
                "centre_of_mass_trace[{i}] = {c:?} is beyond what {} steps can reach",
                m.steps
            ));
        }
    }
    let protocol = scene.protocol();
    let (along, lateral) = protocol.travel(trace[0], trace[trace.len() - 1]);
    if along.to_bits() != m.displacement.to_bits() || lateral.to_bits() != m.lateral.to_bits() {
        return Err(implausible!(
            "displacement {} and lateral {} differ from the trace's {along} and {lateral}",
            m.displacement,
            m.lateral
        ));
    }
    let gait = protocol.score(trace);
    if gait.to_bits() != m.gait_displacement.to_bits() || fitness.to_bits() != gait.to_bits() {
        return Err(implausible!(
            "fitness {fitness} and gait_displacement {} differ from the trace's {gait}",
            m.gait_displacement
        ));
    }
    check_starts(
        scene,
        m,
        gait,
        2.0 * reach * f64::from(scene.actuation_cycles),
    )?;
    let speed = protocol.speed_percent_per_cycle(gait, m.body_length);
    if speed.to_bits() != m.speed_percent_per_cycle.to_bits() {
        return Err(implausible!(
            "speed_percent_per_cycle {} differs from {speed}",
            m.speed_percent_per_cycle
        ));
    }
    Ok(())
}

/// A peer's starts: one fitness per start, each within what the steps can travel, and the
/// scored start's gait their median.
fn check_starts(
    scene: &LocomotionScene,
    m: &LocomotionMetrics,
    gait: f64,
    reach: f64,
) -> Result<(), ImplausibleClaim> {
    let starts = scene.starts.count as usize;
    let expected = if starts > 1 { starts } else { 0 };
    if m.start_fitness.len() != expected {
        return Err(implausible!(
            "start_fitness has {} values, expected {expected} (one per start of {starts}, none \
             for a single start)",
            m.start_fitness.len()
        ));
    }
    if m.start_fitness.is_empty() {
        return Ok(());
    }
    if let Some(f) = m
        .start_fitness
        .iter()
        .find(|f| !(f.is_finite() && f.abs() <= reach))
    {
        return Err(implausible!(
            "start_fitness value {f} is beyond what {} steps can reach",
            m.steps
        ));
    }
    let median = m.start_fitness[Starts::median_start(&m.start_fitness)];
    if median.to_bits() != gait.to_bits() {
        return Err(implausible!(
            "the median of start_fitness, {median}, is not the scored start's gait {gait}"
        ));
    }
    Ok(())
}
