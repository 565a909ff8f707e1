//! The per-voxel passes of a step besides the links and the integration (`integrate.rs`): external
//! loads, gravity, global damping, floor contact with Coulomb friction. Each is a plain loop over
//! flat arrays; the scene decides once which of them exist.

use super::math::Vec3;
use super::scene::FrictionLaw;
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
    /// The scene's friction law (`Floor::friction`).
    pub law: FrictionLaw,
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
        if contact.law == FrictionLaw::Voxcad {
            voxcad_contact(voxels, contact, i, penetration, dt);
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

/// One voxel's contact under [`FrictionLaw::Voxcad`] (the VoxCAD-era Voxelyze's rule, read from
/// its public source and written here): friction from the elastic normal force, the damping
/// force added to the normal without a floor at zero, static only from exactly zero velocity.
fn voxcad_contact(
    voxels: &mut Voxels,
    contact: &mut FloorContact,
    i: usize,
    penetration: f64,
    dt: f64,
) {
    let v = voxels.velocity[i];
    let normal = contact.stiffness[i] * penetration;
    let f = &mut voxels.force[i];
    f.z += normal - contact.damping[i] * v.z;
    let speed = (v.x * v.x + v.y * v.y).sqrt();
    let pull = (f.x * f.x + f.y * f.y).sqrt();
    let friction = voxels.kinetic_friction[i] * normal;
    let stops = if speed == 0.0 {
        pull < voxels.static_friction[i] * normal
    } else if friction * dt < voxels.mass[i] * speed {
        f.x -= friction * v.x / speed;
        f.y -= friction * v.y / speed;
        false
    } else {
        true
    };
    contact.sticking[i] = stops;
    if stops {
        f.x = 0.0;
        f.y = 0.0;
        let p = &mut voxels.momentum[i];
        p.x = 0.0;
        p.y = 0.0;
    }
}

#[cfg(test)]
mod tests;
