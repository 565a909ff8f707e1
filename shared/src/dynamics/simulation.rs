//! The simulation: state arrays, the step loop built from the scene's passes, and observables
//! (centre of mass, momenta, energy) for tasks, tests and studies.

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use super::collide::Collisions;
use super::error::{DynamicsError, Result};
use super::integrate::integrate_pass;
use super::link::{LinkStep, link_energy, link_pass, link_pass_mixed};
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

/// Energy split (J). Gravity's and the external loads' potential is −f·x (in `gravitational`),
/// so only differences are meaningful.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Energy {
    pub kinetic: f64,
    pub elastic: f64,
    pub gravitational: f64,
    pub contact: f64,
}

impl Energy {
    pub fn total(&self) -> f64 {
        self.kinetic + self.elastic + self.gravitational + self.contact
    }
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

    /// Starts the actuation clock now: actuated links follow the scene's sinusoid from here on.
    /// Without an actuation in the scene this does nothing.
    /// Changes the global damping ratio (`DampingParams::global`) from the next step on, e.g. a
    /// heavier damping while a body settles. The time step is unchanged: velocity damping up to
    /// ζ ≈ 1.5 at the lattice's top mode keeps the step stable (h² + 4ζh ≤ 4 at h ≈ 0.58). Refused
    /// where the scene's own value would be: negative or not finite.
    pub fn set_global_damping(&mut self, zeta: f64) -> Result<()> {
        if !(zeta.is_finite() && zeta >= 0.0) {
            return Err(DynamicsError::InvalidScene {
                field: "damping.global",
                value: zeta,
            });
        }
        self.global_damping = global_damping_constants(&self.voxels, self.scene.voxel_size, zeta);
        self.rebuild_passes();
        Ok(())
    }

    pub fn start_actuation(&mut self) {
        if self.scene.actuation.is_some() {
            self.actuation_time = Some(self.time);
            self.rebuild_passes();
        }
    }

    /// Sets the actuation's phase at its start, rad (the scene's `actuation.phase`), e.g. to
    /// switch a settled body on later in the cycle; a scene without actuation has none to set.
    pub fn set_actuation_phase(&mut self, phase: f64) {
        if let Some(actuation) = self.scene.actuation.as_mut() {
            actuation.phase = phase;
        }
    }

    /// Holds voxel `i` in place (position and orientation), like a clamp.
    pub fn fix_voxel(&mut self, i: usize) -> Result<()> {
        self.check_index(i)?;
        self.voxels.inv_mass[i] = 0.0;
        self.voxels.inv_inertia[i] = 0.0;
        Ok(())
    }

    /// Tilts the floor to `incline` rad towards the floor's `downhill` direction, e.g. to raise
    /// an incline slowly as in a tilt-table friction measurement. Needs a floor and
    /// |incline| < π/2.
    pub fn set_incline(&mut self, incline: f64) -> Result<()> {
        let valid = incline.abs() < std::f64::consts::FRAC_PI_2; // false for NaN
        let Some(floor) = self.scene.floor.as_mut().filter(|_| valid) else {
            return Err(DynamicsError::InvalidScene {
                field: "floor.incline",
                value: incline,
            });
        };
        floor.incline = incline;
        self.gravity = tilted_gravity(self.scene.gravity, incline, floor.downhill);
        Ok(())
    }

    /// Applies a constant external force (N) to voxel `i`, in addition to any other.
    pub fn add_external_force(&mut self, i: usize, force: Vec3) -> Result<()> {
        self.check_index(i)?;
        if self.external.is_empty() {
            self.external = vec![Vec3::ZERO; self.voxels.len()];
        }
        self.external[i] += force;
        self.rebuild_passes();
        Ok(())
    }

    /// Sets the velocity of every voxel to `v + ω × (x − centre)` and its spin to ω: a rigid motion.
    pub fn set_rigid_velocity(&mut self, v: Vec3, omega: Vec3, centre: Vec3) {
        let vx = &mut self.voxels;
        for i in 0..vx.len() {
            let vel = v + omega.cross(vx.position[i] - centre);
            vx.velocity[i] = vel;
            vx.momentum[i] = vel * vx.mass[i];
            vx.angular_velocity[i] = omega;
            vx.angular_momentum[i] = omega * (vx.mass[i] * self.scene.voxel_size.powi(2) / 6.0);
        }
    }

    /// Sets the velocity (m/s) of voxel `i`.
    pub fn set_velocity(&mut self, i: usize, velocity: Vec3) -> Result<()> {
        self.check_index(i)?;
        self.voxels.velocity[i] = velocity;
        self.voxels.momentum[i] = velocity * self.voxels.mass[i];
        Ok(())
    }

    /// Index of the voxel in grid cell (x, y, z), if filled.
    pub fn voxel_at(&self, cell: [usize; 3]) -> Option<usize> {
        self.voxels
            .cell
            .iter()
            .position(|c| [usize::from(c[0]), usize::from(c[1]), usize::from(c[2])] == cell)
    }

    fn check_index(&self, i: usize) -> Result<()> {
        if i < self.voxels.len() {
            Ok(())
        } else {
            Err(DynamicsError::VoxelIndex {
                index: i,
                count: self.voxels.len(),
            })
        }
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

    pub fn dt(&self) -> f64 {
        self.dt
    }

    pub fn time(&self) -> f64 {
        self.time
    }

    pub fn steps(&self) -> u64 {
        self.steps
    }

    pub fn scene(&self) -> &DynamicScene {
        &self.scene
    }

    pub fn voxel_count(&self) -> usize {
        self.voxels.len()
    }

    pub fn link_count(&self) -> usize {
        self.links.len()
    }

    pub fn positions(&self) -> &[Vec3] {
        &self.voxels.position
    }

    pub fn velocities(&self) -> &[Vec3] {
        &self.voxels.velocity
    }

    pub fn orientations(&self) -> &[super::math::Quat] {
        &self.voxels.orientation
    }

    /// Grid cell of each voxel.
    pub fn cells(&self) -> &[[u16; 3]] {
        &self.voxels.cell
    }

    pub fn centre_of_mass(&self) -> Vec3 {
        let v = &self.voxels;
        let (mut sum, mut mass) = (Vec3::ZERO, 0.0);
        for i in 0..v.len() {
            sum += v.position[i] * v.mass[i];
            mass += v.mass[i];
        }
        sum * (1.0 / mass)
    }

    /// Largest voxel speed, m/s.
    pub fn max_speed(&self) -> f64 {
        self.voxels
            .velocity
            .iter()
            .map(|v| v.norm2())
            .fold(0.0, f64::max)
            .sqrt()
    }

    pub fn linear_momentum(&self) -> Vec3 {
        self.voxels
            .momentum
            .iter()
            .fold(Vec3::ZERO, |acc, &p| acc + p)
    }

    /// Total angular momentum about the origin: Σ x × p + spin.
    pub fn angular_momentum(&self) -> Vec3 {
        let v = &self.voxels;
        (0..v.len()).fold(Vec3::ZERO, |acc, i| {
            acc + v.position[i].cross(v.momentum[i]) + v.angular_momentum[i]
        })
    }

    pub fn energy(&self) -> Energy {
        let v = &self.voxels;
        let s = self.scene.voxel_size;
        let step = LinkStep {
            voxel_size: s,
            actuation_factor: self.actuation_factor(),
        };
        let actuated_reach = self.actuated_floor_reach(step.actuation_factor);
        let mut kinetic = 0.0;
        let mut gravitational = 0.0;
        let mut contact = 0.0;
        for i in 0..v.len() {
            kinetic += 0.5 * v.momentum[i].norm2() * v.inv_mass[i]
                + 0.5 * v.angular_momentum[i].norm2() * v.inv_inertia[i];
            gravitational -= v.mass[i] * self.gravity.dot(v.position[i]);
            if let Some(f) = self.external.get(i) {
                gravitational -= f.dot(v.position[i]);
            }
            if !self.floor.stiffness.is_empty() {
                let reach = if v.actuated[i] {
                    actuated_reach
                } else {
                    0.5 * s
                };
                let pen = (reach - v.position[i].z).max(0.0);
                contact += 0.5 * self.floor.stiffness[i] * pen * pen;
            }
        }
        let mut elastic = link_energy(&self.links, v, step);
        if self.poisson.is_active() {
            elastic += self.poisson.energy(&self.links, v, step);
        }
        Energy {
            kinetic,
            elastic,
            gravitational,
            contact,
        }
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
mod tests {
    use super::super::math::Quat;
    use super::super::state::TOP_EIGENVALUE;
    use super::*;
    use crate::material::{Material, MaterialId};
    use crate::voxel::GridDims;

    /// Largest eigenvalue of M⁻¹K (translations and rotations) of an n-block at rest, in units
    /// of (EA/L)/m, by power iteration on the link pass around the rest state.
    fn top_eigenvalue(n: [usize; 3]) -> f64 {
        let grid = VoxelGrid::filled(GridDims::new(n[0], n[1], n[2]), MaterialId(0));
        let palette = Palette(vec![Material::new("rubber", 1e6, 0.35)]);
        let s = 0.01;
        let (mut v, links) = build_state(&grid, &palette, s, 0.0).unwrap();
        let rest = v.position.clone();
        let count = v.len();
        // A deterministic start vector with a component along every direction.
        let mut u: Vec<f64> = (0..6 * count)
            .map(|i| ((i * 7919) % 13) as f64 - 6.0)
            .collect();
        let eps = 1e-9;
        let mut lambda = 0.0;
        for _ in 0..300 {
            let norm = u.iter().map(|x| x * x).sum::<f64>().sqrt();
            u.iter_mut().for_each(|x| *x /= norm);
            for i in 0..count {
                let (sm, si) = (v.mass[i].sqrt(), (v.mass[i] * s * s / 6.0).sqrt());
                let t = Vec3::new(u[6 * i], u[6 * i + 1], u[6 * i + 2]);
                let r = Vec3::new(u[6 * i + 3], u[6 * i + 4], u[6 * i + 5]);
                v.position[i] = rest[i] + t * (eps / sm);
                v.orientation[i] = Quat::from_rotation_vector(r * (eps / si));
                v.force[i] = Vec3::ZERO;
                v.torque[i] = Vec3::ZERO;
            }
            let step = LinkStep {
                voxel_size: s,
                actuation_factor: 1.0,
            };
            link_pass::<false, false>(&links, &mut v, step);
            let mut w = vec![0.0; 6 * count];
            for i in 0..count {
                let (sm, si) = (v.mass[i].sqrt(), (v.mass[i] * s * s / 6.0).sqrt());
                let f = v.force[i] * (-1.0 / (eps * sm));
                let t = v.torque[i] * (-1.0 / (eps * si));
                w[6 * i..6 * i + 6].copy_from_slice(&[f.x, f.y, f.z, t.x, t.y, t.z]);
            }
            lambda = w.iter().zip(&u).map(|(a, b)| a * b).sum::<f64>();
            u = w;
        }
        lambda / (1e6 * s / (1000.0 * s * s * s))
    }

    #[test]
    fn damping_reference_bounds_the_lattice_spectrum() {
        // The stiffness-proportional link damping gives the top mode ζ·√(λ/TOP_EIGENVALUE); it
        // must not exceed ζ (stability of the explicit step), nor fall far below it.
        for (n, expected) in [([2, 1, 1], 5.0), ([6, 6, 6], 13.1), ([12, 12, 1], 11.9)] {
            let lambda = top_eigenvalue(n);
            assert!(lambda < TOP_EIGENVALUE, "{n:?}: {lambda}");
            assert!((lambda - expected).abs() < 0.1, "{n:?}: {lambda}");
        }
    }
}
