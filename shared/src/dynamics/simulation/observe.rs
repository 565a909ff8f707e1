//! What a running simulation shows: its clock, its state arrays, and the observables (centre of
//! mass, momenta, energy) that tasks, tests and studies read. Nothing here changes the state.

use super::super::link::{LinkStep, link_energy};
use super::super::math::{Quat, Vec3};
use super::super::scene::DynamicScene;
use super::Simulation;

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

impl Simulation {
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

    pub fn orientations(&self) -> &[Quat] {
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
