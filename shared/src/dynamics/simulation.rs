//! The simulation: state arrays and the step loop built from the scene's passes. What it shows
//! (centre of mass, momenta, energy) is in `observe`, how a task sets it up beyond its scene in
//! `setup`.

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use super::collide::Collisions;
use super::error::Result;
use super::integrate::integrate_pass;
use super::link::{LinkStep, link_pass, link_pass_mixed};
use super::math::Vec3;
use super::parallel::Threaded;
use super::passes::{
    FloorContact, external_force_pass, floor_pass, global_damping_pass, gravity_pass,
};
use super::poisson::PoissonCoupling;
use super::scene::{DynamicScene, LinkPrecision};
use super::single::SingleCopy;
use super::state::{Links, Voxels, build_state, link_damping_time};
use crate::material::Palette;
use crate::voxel::VoxelGrid;

mod observe;
mod setup;

pub use observe::Energy;

/// Why a simulation stopped before its end.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, thiserror::Error)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum DivergenceReason {
    #[error("non-finite state")]
    NonFinite,
    #[error("link strain {strain:.3} above the limit {limit}")]
    Strain { strain: f64, limit: f64 },
    #[error("a voxel moved {travel:.3} voxel sizes in one step, above the limit {limit}")]
    Runaway { travel: f64, limit: f64 },
}

/// A diverged simulation: the reason, the simulated time and the step at which it was detected.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, thiserror::Error)]
#[error("diverged at t = {time} s (step {step}): {reason}")]
pub struct Divergence {
    pub reason: DivergenceReason,
    pub time: f64,
    pub step: u64,
}

/// One pass of the step loop. The list is chosen once from the scene: a disabled pass is absent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    Links { damped: bool, actuated: bool },
    Poisson,
    ExternalForces,
    Gravity,
    GlobalDamping,
    Collisions,
    Floor,
    Integrate,
}

/// A running dynamic simulation of one voxel body.
#[derive(Clone, Debug)]
pub struct Simulation {
    scene: DynamicScene,
    voxels: Voxels,
    links: Links,
    passes: Vec<Pass>,
    external: Vec<Vec3>,
    global_damping: (Vec<f64>, Vec<f64>),
    floor: FloorContact,
    collisions: Collisions,
    poisson: PoissonCoupling,
    gravity: Vec3,
    dt: f64,
    time: f64,
    steps: u64,
    /// The divergence that stopped the simulation, if one did: later steps return it unchanged.
    diverged: Option<Divergence>,
    actuation_time: Option<f64>,
    /// Built at the first step run inside a thread pool (see [`Simulation::step`]).
    threaded: Option<Threaded>,
    /// The mixed-precision kernel's `f32` copy (`LinkPrecision::Mixed`), else none; written from
    /// the state at every link pass.
    single: Option<SingleCopy>,
}

impl Simulation {
    /// Builds the simulation of a voxel design. With a floor, the body is lowered so that its
    /// lowest voxels just touch it.
    pub fn new(grid: &VoxelGrid, palette: &Palette, scene: &DynamicScene) -> Result<Self> {
        scene.validate()?;
        let s = scene.voxel_size;
        let (mut voxels, mut links) = build_state(grid, palette, s, scene.damping.link)?;
        let n = voxels.len();
        let mut poisson = PoissonCoupling::default();
        if scene.poisson && voxels.poisson_ratio.iter().any(|&nu| nu != 0.0) {
            poisson = PoissonCoupling::apply_to_links(&voxels, &mut links, s);
            // The axial stiffness changed: so did the lattice's top frequency.
            for k in 0..links.len() {
                let m_min = voxels.mass[links.a[k] as usize].min(voxels.mass[links.b[k] as usize]);
                links.damping_time[k] =
                    link_damping_time(links.axial[k], m_min, scene.damping.link);
            }
        }
        if scene.floor.is_some() {
            let lowest = voxels
                .position
                .iter()
                .map(|p| p.z)
                .fold(f64::INFINITY, f64::min);
            for p in &mut voxels.position {
                p.z -= lowest - 0.5 * s;
            }
        }
        let gravity = match &scene.floor {
            Some(f) => tilted_gravity(scene.gravity, f.incline, f.downhill),
            None => Vec3::new(0.0, 0.0, -scene.gravity),
        };
        let mut floor = FloorContact::default();
        if let Some(f) = &scene.floor {
            floor.stiffness = voxels
                .stiffness
                .iter()
                .map(|k| k * f.stiffness_factor)
                .collect();
            floor.damping = (0..n)
                .map(|i| 2.0 * scene.damping.contact * (voxels.mass[i] * floor.stiffness[i]).sqrt())
                .collect();
            floor.sticking = vec![false; n];
            floor.law = f.friction;
        }
        let global_damping = global_damping_constants(&voxels, s, scene.damping.global);
        let k_max = links
            .axial
            .iter()
            .copied()
            .chain(floor.stiffness.iter().copied())
            .chain(voxels.stiffness.iter().copied())
            .fold(0.0, f64::max);
        let m_min = voxels.mass.iter().copied().fold(f64::INFINITY, f64::min);
        let dt = scene.dt_fraction / (2.0 * PI * (k_max / m_min).sqrt());
        let collisions = if scene.collisions {
            Collisions::new(&voxels, s)
        } else {
            Collisions::default()
        };
        let mut sim = Self {
            scene: scene.clone(),
            voxels,
            links,
            passes: Vec::new(),
            external: Vec::new(),
            global_damping,
            floor,
            collisions,
            poisson,
            gravity,
            dt,
            time: 0.0,
            steps: 0,
            diverged: None,
            actuation_time: None,
            threaded: None,
            single: None,
        };
        if scene.link_precision == LinkPrecision::Mixed {
            sim.single = Some(SingleCopy::new(&sim.links, sim.voxels.len()));
        }
        sim.rebuild_passes();
        Ok(sim)
    }

    fn rebuild_passes(&mut self) {
        let sc = &self.scene;
        let mut passes = Vec::new();
        if !self.links.is_empty() {
            passes.push(Pass::Links {
                damped: sc.damping.link > 0.0,
                actuated: sc.actuation.is_some()
                    && self.actuation_time.is_some()
                    && self.voxels.actuated.iter().any(|&a| a),
            });
        }
        if self.poisson.is_active() {
            passes.push(Pass::Poisson);
        }
        if !self.external.is_empty() {
            passes.push(Pass::ExternalForces);
        }
        if self.gravity != Vec3::ZERO {
            passes.push(Pass::Gravity);
        }
        if !self.global_damping.0.is_empty() {
            passes.push(Pass::GlobalDamping);
        }
        if sc.collisions {
            passes.push(Pass::Collisions);
        }
        if sc.floor.is_some() {
            passes.push(Pass::Floor);
        }
        passes.push(Pass::Integrate);
        self.passes = passes;
    }

    /// The passes of the step loop, in order.
    pub fn passes(&self) -> &[Pass] {
        &self.passes
    }

    /// Runs only the given passes (for the per-pass benchmark); must end with `Integrate`.
    pub fn set_passes(&mut self, passes: Vec<Pass>) {
        self.passes = passes;
    }

    /// Linear rest-length factor λ of actuated material now: the cube root of the volume factor.
    pub fn actuation_factor(&self) -> f64 {
        match (&self.scene.actuation, self.actuation_time) {
            (Some(a), Some(t0)) => {
                let phase = 2.0 * PI * (self.time - t0) / a.period + a.phase;
                (1.0 + a.amplitude_volume * phase.sin()).cbrt()
            }
            _ => 1.0,
        }
    }

    /// How far above the floor an actuated voxel's centre is when it starts to touch: half its
    /// rest size, or half its actuated size (`actuation_factor` λ) with `Floor::actuated_contact`.
    fn actuated_floor_reach(&self, actuation_factor: f64) -> f64 {
        let half = 0.5 * self.scene.voxel_size;
        match &self.scene.floor {
            Some(f) if f.actuated_contact => half * actuation_factor,
            _ => half,
        }
    }

    /// Advances one time step. On divergence the state is left as it was found diverged and
    /// every further call returns the same outcome.
    ///
    /// Called inside a `rayon` thread pool (`ThreadPool::install`), the step shares its link pass
    /// and its integration among the pool's threads, with the same bits as on one thread for any
    /// number of threads (`super::parallel`); elsewhere it runs on the calling thread alone.
    pub fn step(&mut self) -> std::result::Result<(), Divergence> {
        if let Some(d) = &self.diverged {
            return Err(d.clone());
        }
        let result = self.advance();
        if let Err(d) = &result {
            self.diverged = Some(d.clone());
        }
        result
    }

    /// One step of every pass, then the divergence checks.
    fn advance(&mut self) -> std::result::Result<(), Divergence> {
        let link_step = LinkStep {
            voxel_size: self.scene.voxel_size,
            actuation_factor: self.actuation_factor(),
        };
        let mut max_strain = 0.0;
        let mut summary = None;
        let in_pool = rayon::current_thread_index().is_some();
        for k in 0..self.passes.len() {
            match self.passes[k] {
                Pass::Links { damped, actuated } => {
                    max_strain = match (damped, actuated) {
                        (false, false) => self.links::<false, false>(in_pool, link_step),
                        (true, false) => self.links::<true, false>(in_pool, link_step),
                        (false, true) => self.links::<false, true>(in_pool, link_step),
                        (true, true) => self.links::<true, true>(in_pool, link_step),
                    };
                }
                Pass::Poisson => self.poisson.pass(&self.links, &mut self.voxels, link_step),
                Pass::ExternalForces => external_force_pass(&mut self.voxels, &self.external),
                Pass::Gravity => gravity_pass(&mut self.voxels, self.gravity),
                Pass::GlobalDamping => global_damping_pass(
                    &mut self.voxels,
                    &self.global_damping.0,
                    &self.global_damping.1,
                ),
                Pass::Collisions => self
                    .collisions
                    .pass(&mut self.voxels, self.scene.voxel_size),
                Pass::Floor => {
                    let actuated_reach = self.actuated_floor_reach(link_step.actuation_factor);
                    floor_pass(
                        &mut self.voxels,
                        &mut self.floor,
                        0.5 * self.scene.voxel_size,
                        actuated_reach,
                        self.dt,
                    )
                }
                Pass::Integrate => {
                    summary = Some(if in_pool {
                        Threaded::integrate(&mut self.voxels, self.dt)
                    } else {
                        integrate_pass(&mut self.voxels, self.dt)
                    });
                }
            }
        }
        self.time += self.dt;
        self.steps += 1;
        let limits = &self.scene.divergence;
        let diverged = |reason| Divergence {
            reason,
            time: self.time,
            step: self.steps,
        };
        if let Some(sum) = summary {
            if !sum.checksum.is_finite() || !max_strain.is_finite() {
                return Err(diverged(DivergenceReason::NonFinite));
            }
            let travel = sum.max_speed2.sqrt() * self.dt / self.scene.voxel_size;
            if travel > limits.max_step_travel {
                return Err(diverged(DivergenceReason::Runaway {
                    travel,
                    limit: limits.max_step_travel,
                }));
            }
        }
        if max_strain > limits.max_strain {
            return Err(diverged(DivergenceReason::Strain {
                strain: max_strain,
                limit: limits.max_strain,
            }));
        }
        Ok(())
    }

    /// The link pass, on the current pool's threads when `in_pool`; returns the largest strain.
    fn links<const DAMPED: bool, const ACTUATED: bool>(
        &mut self,
        in_pool: bool,
        step: LinkStep,
    ) -> f64 {
        let (l, v) = (&self.links, &mut self.voxels);
        if let Some(single) = self.single.as_mut() {
            single.copy_state::<DAMPED>(v);
        }
        let single = self.single.as_ref();
        if in_pool {
            self.threaded
                .get_or_insert_with(|| Threaded::new(l, v.len()))
                .link_pass::<DAMPED, ACTUATED>(l, v, single, step)
        } else if let Some(single) = single {
            link_pass_mixed::<DAMPED, ACTUATED>(l, single, v, step)
        } else {
            link_pass::<DAMPED, ACTUATED>(l, v, step)
        }
    }

    /// Runs for `duration` seconds (rounded up to whole steps).
    pub fn run_for(&mut self, duration: f64) -> std::result::Result<(), Divergence> {
        let steps = (duration / self.dt).ceil() as u64;
        self.run_steps(steps)
    }

    pub fn run_steps(&mut self, steps: u64) -> std::result::Result<(), Divergence> {
        for _ in 0..steps {
            self.step()?;
        }
        Ok(())
    }
}

/// Gravity of magnitude `g` tilted by `incline` rad from −Z towards the floor direction
/// `downhill` (rad from +X towards +Y). Downhill along +X is computed without the azimuth's
/// sine and cosine, so scenes written before the azimuth existed keep their bits.
fn tilted_gravity(g: f64, incline: f64, downhill: f64) -> Vec3 {
    let along = g * incline.sin();
    if downhill == 0.0 {
        Vec3::new(along, 0.0, -g * incline.cos())
    } else {
        Vec3::new(
            along * downhill.cos(),
            along * downhill.sin(),
            -g * incline.cos(),
        )
    }
}

/// Per voxel, the linear and angular coefficients of velocity damping at ratio `zeta` of each
/// voxel's own critical damping (empty for 0: the pass is then left out of the loop).
fn global_damping_constants(voxels: &Voxels, s: f64, zeta: f64) -> (Vec<f64>, Vec<f64>) {
    if zeta <= 0.0 {
        return (Vec::new(), Vec::new());
    }
    (0..voxels.len())
        .map(|i| {
            let (m, k) = (voxels.mass[i], voxels.stiffness[i]);
            (
                2.0 * zeta * (m * k).sqrt(),
                2.0 * zeta * (m * s * s / 6.0 * k * s * s / 12.0).sqrt(),
            )
        })
        .unzip()
}

#[cfg(test)]
mod tests;
