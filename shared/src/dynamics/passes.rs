//! The per-voxel passes of a step besides the links: external loads, gravity, global damping,
//! floor contact with Coulomb friction, and the symplectic Euler integration. Each is a plain loop
//! over flat arrays; the scene decides once which of them exist.

use super::math::{Quat, Vec3};
use super::state::Voxels;

/// Adds a constant per-voxel external force (N).
#[inline(never)]
pub fn external_force_pass(voxels: &mut Voxels, external: &[Vec3]) {
    for (f, e) in voxels.force.iter_mut().zip(external) {
        *f += *e;
    }
}

/// Adds m·g to every voxel (g in m/s², a vector so an incline can tilt it).
#[inline(never)]
pub fn gravity_pass(voxels: &mut Voxels, gravity: Vec3) {
    for (f, &m) in voxels.force.iter_mut().zip(&voxels.mass) {
        *f += gravity * m;
    }
}

/// Damps every voxel's absolute velocity and spin with the per-voxel coefficients (N·s/m, N·m·s).
#[inline(never)]
pub fn global_damping_pass(voxels: &mut Voxels, linear: &[f64], angular: &[f64]) {
    for i in 0..voxels.len() {
        voxels.force[i] -= voxels.velocity[i] * linear[i];
        voxels.torque[i] -= voxels.angular_velocity[i] * angular[i];
    }
}

/// Per-voxel contact constants of the floor pass.
#[derive(Clone, Debug, Default)]
pub struct FloorContact {
    /// Penalty stiffness, N/m.
    pub stiffness: Vec<f64>,
    /// Normal damping coefficient, N·s/m.
    pub damping: Vec<f64>,
    /// Static friction state: true while the voxel sticks to the floor.
    pub sticking: Vec<bool>,
}

/// Floor at z = 0 with penalty contact (a voxel touches when its centre is within half its size:
/// `half_size`, or `actuated_half_size` for an actuated voxel) and Coulomb friction with a
/// static/kinetic state per voxel. Runs after every other force pass, because sticking depends on
/// the voxel's total tangential force.
#[inline(never)]
pub fn floor_pass(
    voxels: &mut Voxels,
    contact: &mut FloorContact,
    half_size: f64,
    actuated_half_size: f64,
    dt: f64,
) {
    for i in 0..voxels.len() {
        let reach = if voxels.actuated[i] {
            actuated_half_size
        } else {
            half_size
        };
        let penetration = reach - voxels.position[i].z;
        if penetration <= 0.0 {
            contact.sticking[i] = false;
            continue;
        }
        let v = voxels.velocity[i];
        // No adhesion: the floor only pushes.
        let normal = (contact.stiffness[i] * penetration - contact.damping[i] * v.z).max(0.0);
        let f = &mut voxels.force[i];
        f.z += normal;
        let (ftx, fty) = (f.x, f.y);
        let tangential_force = (ftx * ftx + fty * fty).sqrt();
        let holding = tangential_force <= voxels.static_friction[i] * normal;
        let p = &mut voxels.momentum[i];
        if contact.sticking[i] {
            if holding {
                f.x = 0.0;
                f.y = 0.0;
                p.x = 0.0;
                p.y = 0.0;
                continue;
            }
            contact.sticking[i] = false;
        }
        // Kinetic: μk·N against the sliding direction (or against the pull when starting). A
        // voxel slower than what friction removes in one step stops and sticks, if static
        // friction can hold it (this also makes a voxel landing at rest stick).
        let friction = voxels.kinetic_friction[i] * normal;
        let tangential_momentum = (p.x * p.x + p.y * p.y).sqrt();
        if holding && tangential_momentum <= friction * dt {
            f.x = 0.0;
            f.y = 0.0;
            p.x = 0.0;
            p.y = 0.0;
            contact.sticking[i] = true;
            continue;
        }
        let speed = (v.x * v.x + v.y * v.y).sqrt();
        let (dir_x, dir_y) = if speed > 0.0 {
            (v.x / speed, v.y / speed)
        } else if tangential_force > 0.0 {
            (ftx / tangential_force, fty / tangential_force)
        } else {
            (0.0, 0.0)
        };
        f.x -= friction * dir_x;
        f.y -= friction * dir_y;
        // Friction cannot reverse the motion within a step: if it would, the voxel stops.
        let (px, py) = (p.x + f.x * dt, p.y + f.y * dt);
        if px * dir_x + py * dir_y <= 0.0 && holding {
            f.x = 0.0;
            f.y = 0.0;
            p.x = 0.0;
            p.y = 0.0;
            contact.sticking[i] = true;
        }
    }
}

/// What the integration saw, for divergence detection.
#[derive(Clone, Copy, Debug)]
pub struct IntegrationSummary {
    /// Largest squared speed, m²/s².
    pub max_speed2: f64,
    /// Sum of all position and momentum components: non-finite iff some state is.
    pub checksum: f64,
}

/// Semi-implicit (symplectic) Euler: momenta from the forces, then positions and orientations
/// from the new momenta. Clears the force accumulators for the next step.
#[inline(never)]
pub fn integrate_pass(voxels: &mut Voxels, dt: f64) -> IntegrationSummary {
    let mut max_speed2: f64 = 0.0;
    let mut checksum = 0.0;
    let half_dt = 0.5 * dt;
    for i in 0..voxels.len() {
        let p = voxels.momentum[i] + voxels.force[i] * dt;
        voxels.momentum[i] = p;
        let v = p * voxels.inv_mass[i];
        voxels.velocity[i] = v;
        let x = voxels.position[i] + v * dt;
        voxels.position[i] = x;
        let l = voxels.angular_momentum[i] + voxels.torque[i] * dt;
        voxels.angular_momentum[i] = l;
        let w = l * voxels.inv_inertia[i];
        voxels.angular_velocity[i] = w;
        let q = voxels.orientation[i];
        // q̇ = ½ ω q (ω in the world frame), then back onto the unit sphere.
        let dq = Quat {
            w: 0.0,
            x: w.x,
            y: w.y,
            z: w.z,
        }
        .compose(q);
        voxels.orientation[i] = Quat {
            w: q.w + half_dt * dq.w,
            x: q.x + half_dt * dq.x,
            y: q.y + half_dt * dq.y,
            z: q.z + half_dt * dq.z,
        }
        .normalized();
        voxels.force[i] = Vec3::ZERO;
        voxels.torque[i] = Vec3::ZERO;
        max_speed2 = max_speed2.max(v.norm2());
        checksum += x.x + x.y + x.z + l.x + l.y + l.z;
    }
    IntegrationSummary {
        max_speed2,
        checksum,
    }
}
