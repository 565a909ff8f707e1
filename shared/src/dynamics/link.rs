//! The link pass: 3-D Euler–Bernoulli frame forces and moments between face-adjacent voxels.
//!
//! Large rotations are handled co-rotationally. The link frame is the *mid rotation* of the two
//! voxels, q_mid = q_a · (q_a* q_b)^½, so a rigid rotation of the pair leaves the local state
//! unchanged. In that frame (link axis cyclically shifted to x) voxel a sits at the origin, voxel b
//! at d = (L + δ, v, w), and the end rotations are −φ/2 and +φ/2 with φ the rotation vector of
//! q_a* q_b. The linear frame element stiffness then gives (forces on b, moments on a and b):
//!
//! ```text
//! F_b = (−EA/L·δ, −12EI/L³·v, −12EI/L³·w)
//! M_a = ( GJ/L·φx,  EI/L·φy − 6EI/L²·w,  EI/L·φz + 6EI/L²·v)
//! M_b = (−GJ/L·φx, −EI/L·φy − 6EI/L²·w, −EI/L·φz + 6EI/L²·v)
//! ```
//!
//! (the 4EI/L and 2EI/L end terms combine into ±EI/L because the end rotations are opposite, and
//! the 6EI/L² terms in φ cancel for the same reason). Finite strains leave a small moment
//! imbalance M_a + M_b + d × F_b; it is split between the ends so that every link conserves
//! angular momentum exactly, as a rigid body needs.

use super::math::{Quat, Vec3};
use super::state::{Links, Voxels};

/// Per-step inputs of the link pass.
#[derive(Clone, Copy, Debug)]
pub struct LinkStep {
    /// Voxel size s, m (the rest length of a passive link).
    pub voxel_size: f64,
    /// Linear rest-length factor λ(t) of actuated material (1 when not actuating).
    pub actuation_factor: f64,
}

/// Adds every link's forces and moments to the voxels' accumulators. Returns the largest axial
/// strain |δ|/L seen, for divergence detection. `DAMPED` and `ACTUATED` select the variant at
/// compile time so a scene without link damping or actuation pays nothing for them.
#[inline(never)]
pub fn link_pass<const DAMPED: bool, const ACTUATED: bool>(
    links: &Links,
    voxels: &mut Voxels,
    step: LinkStep,
) -> f64 {
    let s = step.voxel_size;
    let inv_s = 1.0 / s;
    let stretch = step.actuation_factor - 1.0;
    let mut max_strain: f64 = 0.0;
    let position = &voxels.position;
    let orientation = &voxels.orientation;
    let velocity = &voxels.velocity;
    let angular_velocity = &voxels.angular_velocity;
    let force = &mut voxels.force;
    let torque = &mut voxels.torque;
    for k in 0..links.len() {
        let (ia, ib) = (links.a[k] as usize, links.b[k] as usize);
        let axis = links.axis[k];
        let qa = orientation[ia];
        let mut q_rel = qa.conj().compose(orientation[ib]);
        if q_rel.w < 0.0 {
            q_rel = q_rel.scaled(-1.0);
        }
        // √q_rel = (q_rel + 1)/|q_rel + 1| for a unit quaternion with w ≥ 0, and
        // |q_rel + 1|² = 2 + 2w: the frame is built from the unnormalised product with that
        // norm folded into the matrix (no square root).
        let half = Quat {
            w: q_rel.w + 1.0,
            ..q_rel
        };
        let frame = qa
            .compose(half)
            .to_matrix_with_scale(1.0 / (qa.norm2() * (1.0 + q_rel.w)));
        let r_world = position[ib] - position[ia];
        let d = frame.apply_transpose(r_world).to_axis(axis);
        let phi = q_rel.rotation_vector().to_axis(axis);

        let rest = if ACTUATED {
            s * (1.0 + links.actuated_fraction[k] * stretch)
        } else {
            s
        };
        let delta = d.x - rest;
        max_strain = max_strain.max(delta.abs());

        // Generalised deformation: the elastic one, plus β times its rate when damped
        // (stiffness-proportional damping through the same element, so it dissipates, leaves
        // rigid motion alone and balances its moments exactly like the elastic forces).
        let (mut e, mut p) = (Vec3::new(delta, d.y, d.z), phi);
        if DAMPED {
            // Rate of d in the link frame, which turns with the mean spin of the pair.
            let spin = (angular_velocity[ia] + angular_velocity[ib]) * 0.5;
            let v_rel = velocity[ib] - velocity[ia] - spin.cross(r_world);
            let beta = links.damping_time[k];
            e += frame.apply_transpose(v_rel).to_axis(axis) * beta;
            p += frame
                .apply_transpose(angular_velocity[ib] - angular_velocity[ia])
                .to_axis(axis)
                * beta;
        }

        let (ka, ks, kc, kb, kt) = (
            links.axial[k],
            links.shear[k],
            links.coupling[k],
            links.bending[k],
            links.torsion[k],
        );
        let f_b = Vec3::new(-ka * e.x, -ks * e.y, -ks * e.z);
        let mut m_a = Vec3::new(kt * p.x, kb * p.y - kc * e.z, kb * p.z + kc * e.y);
        let mut m_b = Vec3::new(-kt * p.x, -kb * p.y - kc * e.z, -kb * p.z + kc * e.y);
        let half_residual = (m_a + m_b + d.cross(f_b)) * 0.5;
        m_a -= half_residual;
        m_b -= half_residual;

        let f_b_world = frame.apply(f_b.unshift_axis(axis));
        let m_a_world = frame.apply(m_a.unshift_axis(axis));
        let m_b_world = frame.apply(m_b.unshift_axis(axis));

        force[ib] += f_b_world;
        force[ia] -= f_b_world;
        torque[ia] += m_a_world;
        torque[ib] += m_b_world;
    }
    max_strain * inv_s
}

/// Elastic energy of all links (J), consistent with the forces of [`link_pass`] to second order.
pub fn link_energy(links: &Links, voxels: &Voxels, step: LinkStep) -> f64 {
    let s = step.voxel_size;
    let stretch = step.actuation_factor - 1.0;
    let mut energy = 0.0;
    for k in 0..links.len() {
        let (ia, ib) = (links.a[k] as usize, links.b[k] as usize);
        let axis = links.axis[k];
        let qa = voxels.orientation[ia];
        let mut q_rel = qa.conj().compose(voxels.orientation[ib]);
        if q_rel.w < 0.0 {
            q_rel = q_rel.scaled(-1.0);
        }
        let half = Quat {
            w: q_rel.w + 1.0,
            ..q_rel
        }
        .normalized();
        let frame = qa.compose(half).to_matrix();
        let d = frame
            .apply_transpose(voxels.position[ib] - voxels.position[ia])
            .to_axis(axis);
        let phi = q_rel.rotation_vector().to_axis(axis);
        let rest = s * (1.0 + links.actuated_fraction[k] * stretch);
        let delta = d.x - rest;
        energy += 0.5
            * (links.axial[k] * delta * delta
                + links.shear[k] * (d.y * d.y + d.z * d.z)
                + links.bending[k] * (phi.y * phi.y + phi.z * phi.z)
                + links.torsion[k] * phi.x * phi.x);
    }
    energy
}
