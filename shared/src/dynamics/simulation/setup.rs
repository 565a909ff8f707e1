//! Setting a simulation up beyond its scene: loads, clamps, velocities, a tilted floor, damping
//! changed mid-run, the actuation's start. Each checks what it is given, as the scene's own
//! values are checked, since tasks call these with values read from configs.

use super::super::error::{DynamicsError, Result};
use super::super::math::Vec3;
use super::{Simulation, global_damping_constants, tilted_gravity};

impl Simulation {
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

    /// Starts the actuation clock now: actuated links follow the scene's sinusoid from here on.
    /// Without an actuation in the scene this does nothing.
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
}
