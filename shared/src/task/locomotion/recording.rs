//! A locomotion run recorded for pictures: the best robot is simulated once more, exactly as its
//! evaluation did (same steps, same bits), while an observer samples the centre of mass densely
//! and keeps every voxel's position and orientation at animation frames. Evaluations never pay
//! for this: only reports and `worker export` call it.

use super::{LocomotionOutcome, LocomotionPhase, LocomotionScene, simulate_locomotion_observed};
use crate::dynamics::Simulation;
use crate::genome::Genome;
use crate::material::MaterialId;
use crate::task::design;
use crate::voxel::GridDims;

/// How densely to record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecordingOptions {
    /// Centre-of-mass samples per actuation cycle (default 20).
    pub samples_per_cycle: u32,
    /// Keep the voxels as an animation frame every this many samples (default 2: ten frames per
    /// cycle, which shows the scooting gait and keeps a ten-cycle GIF to ~100 frames).
    pub frame_every: u32,
}

impl Default for RecordingOptions {
    fn default() -> Self {
        Self {
            samples_per_cycle: 20,
            frame_every: 2,
        }
    }
}

/// Part of a recording: a centre-of-mass sample or a frame, and where the run was.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Simulated time, s.
    pub time: f64,
    pub phase: LocomotionPhase,
}

/// What [`record_locomotion`] kept. Voxel `i` is the i-th voxel of the simulated body (grid order).
#[derive(Clone, Debug)]
pub struct LocomotionRecording {
    /// Edge length of a voxel, m.
    pub voxel_size: f64,
    /// Rest-lattice cell and material of each voxel.
    pub cells: Vec<[u16; 3]>,
    pub materials: Vec<MaterialId>,
    /// Actuation cycles and period of the scene, s.
    pub cycles: u32,
    pub period: f64,
    /// Centre of mass (m) at every settling check, at the end of settling, and at every sample
    /// of every actuation cycle.
    pub centre_of_mass: Vec<(Sample, [f64; 3])>,
    /// When each animation frame was taken (the settled body first).
    pub frames: Vec<Sample>,
    /// Frame-major voxel positions (m) and orientations (w, x, y, z), in f32: a picture needs no
    /// more and a 20×20×20 robot's 100 frames then fit in ~22 MB.
    positions: Vec<[f32; 3]>,
    orientations: Vec<[f32; 4]>,
    /// The evaluation's own result (bit-identical to the run's).
    pub outcome: LocomotionOutcome,
}

impl LocomotionRecording {
    pub fn voxel_count(&self) -> usize {
        self.cells.len()
    }

    /// Positions and orientations of every voxel in frame `k`.
    pub fn frame(&self, k: usize) -> (&[[f32; 3]], &[[f32; 4]]) {
        let n = self.voxel_count();
        (
            &self.positions[k * n..(k + 1) * n],
            &self.orientations[k * n..(k + 1) * n],
        )
    }
}

/// Simulates the robot `genome` makes at `dims` and records it.
pub fn record_locomotion(
    genome: &Genome,
    scene: &LocomotionScene,
    dims: GridDims,
    options: RecordingOptions,
) -> LocomotionRecording {
    let body = design(scene, genome, dims);
    let dynamics = scene.dynamics_at(dims);
    // Taken from the simulation itself at its first call, so they follow its voxel order.
    let mut cells: Vec<[u16; 3]> = Vec::new();
    let mut materials = Vec::new();
    let mut centre_of_mass = Vec::new();
    let mut frames = Vec::new();
    let mut positions = Vec::new();
    let mut orientations = Vec::new();
    let frame_every = options.frame_every.max(1);
    let mut observe = |phase: LocomotionPhase, sim: &Simulation| {
        if cells.is_empty() {
            cells = sim.cells().to_vec();
            materials = cells
                .iter()
                .map(|c| {
                    let [x, y, z] = c.map(usize::from);
                    body.get(x, y, z).unwrap_or(MaterialId(0))
                })
                .collect();
        }
        let sample = Sample {
            time: sim.time(),
            phase,
        };
        let c = sim.centre_of_mass();
        centre_of_mass.push((sample, [c.x, c.y, c.z]));
        let is_frame = match phase {
            LocomotionPhase::Settling => false,
            LocomotionPhase::Settled => true,
            LocomotionPhase::Actuating { sample, .. } => sample % frame_every == 0,
        };
        if is_frame {
            frames.push(sample);
            positions.extend(
                sim.positions()
                    .iter()
                    .map(|p| [p.x as f32, p.y as f32, p.z as f32]),
            );
            orientations.extend(
                sim.orientations()
                    .iter()
                    .map(|q| [q.w as f32, q.x as f32, q.y as f32, q.z as f32]),
            );
        }
    };
    let outcome = simulate_locomotion_observed(
        &body,
        &scene.palette,
        &dynamics,
        &scene.protocol(),
        options.samples_per_cycle,
        &mut observe,
    );
    LocomotionRecording {
        voxel_size: dynamics.voxel_size,
        cells,
        materials,
        cycles: scene.actuation_cycles,
        period: dynamics.actuation.as_ref().map_or(0.0, |a| a.period),
        centre_of_mass,
        frames,
        positions,
        orientations,
        outcome,
    }
}
