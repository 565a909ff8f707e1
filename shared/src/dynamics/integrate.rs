//! The symplectic Euler integration, four voxels at a time.
//!
//! Every voxel's update is independent of the others, so the pass runs in the link kernel's lanes
//! ([`super::lanes`]): four consecutive voxels' state is loaded as whole vectors, regrouped by
//! component, updated lane-wise with exactly the scalar formula's operations in the scalar
//! formula's order (no fused multiply-add), and written back. The state is therefore the same bits
//! as the one-voxel-at-a-time loop ([`integrate_voxel`], which also takes the last `n mod 4`
//! voxels) on every instruction set. Only the checksum, a non-finiteness detector, is summed in
//! another order.

use super::lanes::{
    LANES, Lanes, Lanes4, Portable, Regroup, load_columns3, load_columns4, store_columns4,
    store_image3,
};
use super::math::{Quat, Vec3};
use super::state::Voxels;

/// What the integration saw, for divergence detection.
#[derive(Clone, Copy, Debug)]
pub struct IntegrationSummary {
    /// Largest squared speed, m²/s².
    pub max_speed2: f64,
    /// 0 while every position and angular momentum component is finite, NaN once one is not: a
    /// sum of those components times zero, so that it is the same in any order of summation.
    pub checksum: f64,
}

/// Semi-implicit (symplectic) Euler: momenta from the forces, then positions and orientations
/// from the new momenta. Clears the force accumulators for the next step.
#[inline(never)]
pub fn integrate_pass(voxels: &mut Voxels, dt: f64) -> IntegrationSummary {
    integrate_part(VoxelState::new(voxels), dt)
}

/// [`integrate_pass`] on a part of the voxels (see [`VoxelState::split_at`]).
#[inline(never)]
pub fn integrate_part(state: VoxelState, dt: f64) -> IntegrationSummary {
    #[cfg(target_arch = "x86_64")]
    if let Some(avx2) = pulp::x86::V3::try_new() {
        return pulp::Simd::vectorize(
            avx2,
            Integrate {
                arith: avx2,
                state: &mut Some(state),
                dt,
            },
        );
    }
    integrate_lanes(Portable, state, dt)
}

impl IntegrationSummary {
    /// The summary of two parts together (exact in any order: a maximum and a sum of zeros).
    pub fn and(self, other: Self) -> Self {
        Self {
            max_speed2: self.max_speed2.max(other.max_speed2),
            checksum: self.checksum + other.checksum,
        }
    }
}

/// [`integrate_part`] as a `pulp` operation, compiled with its instruction set enabled. The state
/// goes by reference and is moved out inside (see `link::LinkPass`).
struct Integrate<'a, 'b, A: Regroup> {
    arith: A,
    state: &'a mut Option<VoxelState<'b>>,
    dt: f64,
}

impl<A: Regroup> pulp::WithSimd for Integrate<'_, '_, A> {
    type Output = IntegrationSummary;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> IntegrationSummary {
        let state = self
            .state
            .take()
            .expect("the state is set before the dispatch");
        integrate_lanes(self.arith, state, self.dt)
    }
}

/// The voxels' state as the integration reads and writes it (all of them, or a part).
#[derive(Debug)]
pub struct VoxelState<'a> {
    momentum: &'a mut [Vec3],
    force: &'a mut [Vec3],
    inv_mass: &'a [f64],
    velocity: &'a mut [Vec3],
    position: &'a mut [Vec3],
    angular_momentum: &'a mut [Vec3],
    torque: &'a mut [Vec3],
    inv_inertia: &'a [f64],
    angular_velocity: &'a mut [Vec3],
    orientation: &'a mut [Quat],
}

impl<'a> VoxelState<'a> {
    /// Every array cut to the voxel count, so that one index check covers all of them.
    #[inline(always)]
    pub fn new(voxels: &'a mut Voxels) -> Self {
        let n = voxels.len();
        Self {
            momentum: &mut voxels.momentum[..n],
            force: &mut voxels.force[..n],
            inv_mass: &voxels.inv_mass[..n],
            velocity: &mut voxels.velocity[..n],
            position: &mut voxels.position[..n],
            angular_momentum: &mut voxels.angular_momentum[..n],
            torque: &mut voxels.torque[..n],
            inv_inertia: &voxels.inv_inertia[..n],
            angular_velocity: &mut voxels.angular_velocity[..n],
            orientation: &mut voxels.orientation[..n],
        }
    }

    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// Voxels `..mid` and `mid..` of this part.
    pub fn split_at(self, mid: usize) -> (Self, Self) {
        let (momentum, momentum2) = self.momentum.split_at_mut(mid);
        let (force, force2) = self.force.split_at_mut(mid);
        let (inv_mass, inv_mass2) = self.inv_mass.split_at(mid);
        let (velocity, velocity2) = self.velocity.split_at_mut(mid);
        let (position, position2) = self.position.split_at_mut(mid);
        let (angular_momentum, angular_momentum2) = self.angular_momentum.split_at_mut(mid);
        let (torque, torque2) = self.torque.split_at_mut(mid);
        let (inv_inertia, inv_inertia2) = self.inv_inertia.split_at(mid);
        let (angular_velocity, angular_velocity2) = self.angular_velocity.split_at_mut(mid);
        let (orientation, orientation2) = self.orientation.split_at_mut(mid);
        (
            Self {
                momentum,
                force,
                inv_mass,
                velocity,
                position,
                angular_momentum,
                torque,
                inv_inertia,
                angular_velocity,
                orientation,
            },
            Self {
                momentum: momentum2,
                force: force2,
                inv_mass: inv_mass2,
                velocity: velocity2,
                position: position2,
                angular_momentum: angular_momentum2,
                torque: torque2,
                inv_inertia: inv_inertia2,
                angular_velocity: angular_velocity2,
                orientation: orientation2,
            },
        )
    }
}

#[inline(always)]
fn integrate_lanes<A: Regroup>(arith: A, st: VoxelState, dt: f64) -> IntegrationSummary {
    let n = st.len();
    // Cut to one length here, inside the vectorized function, so that one check covers every
    // array (the lengths that arrive through `pulp`'s call are unrelated to the optimizer).
    let (mut st, _) = st.split_at(n);
    let whole = n - n % LANES;
    let splat = |x: f64| Lanes::splat(arith, x);
    let (dt_l, half_dt, zero) = (splat(dt), splat(0.5 * dt), splat(0.0));
    let mut max_speed2 = zero;
    let mut checksum = zero;
    let load = |block: &[Vec3]| load_columns3(arith, block);
    let store = |block: &mut [Vec3], c: [Lanes4<A>; 3]| {
        store_image3(arith, block, arith.image3([c[0].v, c[1].v, c[2].v]));
    };
    for i0 in (0..whole).step_by(LANES) {
        let r = i0..i0 + LANES;
        let f = load(&st.force[r.clone()]);
        let m = load(&st.momentum[r.clone()]);
        let p = three(|c| m[c] + f[c] * dt_l);
        store(&mut st.momentum[r.clone()], p);
        let inv_m = Lanes::load(arith, st.inv_mass, i0);
        let v = three(|c| p[c] * inv_m);
        store(&mut st.velocity[r.clone()], v);
        let x0 = load(&st.position[r.clone()]);
        let x = three(|c| x0[c] + v[c] * dt_l);
        store(&mut st.position[r.clone()], x);
        let t = load(&st.torque[r.clone()]);
        let l0 = load(&st.angular_momentum[r.clone()]);
        let l = three(|c| l0[c] + t[c] * dt_l);
        store(&mut st.angular_momentum[r.clone()], l);
        let inv_i = Lanes::load(arith, st.inv_inertia, i0);
        let w = three(|c| l[c] * inv_i);
        store(&mut st.angular_velocity[r.clone()], w);

        let block = &mut st.orientation[r.clone()];
        let [qw, qx, qy, qz] = load_columns4(arith, block);
        // ½ (0, ω) q term by term as `Quat::compose` computes it, the zero products included.
        let [wx, wy, wz] = w;
        let dq = [
            zero * qw - wx * qx - wy * qy - wz * qz,
            zero * qx + wx * qw + wy * qz - wz * qy,
            zero * qy - wx * qz + wy * qw + wz * qx,
            zero * qz + wx * qy - wy * qx + wz * qw,
        ];
        let q = [qw, qx, qy, qz];
        let q = four(|c| q[c] + half_dt * dq[c]);
        let norm = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
        let scale = splat(1.0) / norm;
        store_columns4(arith, block, four(|c| q[c] * scale));

        st.force[r.clone()].fill(Vec3::ZERO);
        st.torque[r].fill(Vec3::ZERO);
        let speed2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        max_speed2.v = arith.max_abs(max_speed2.v, speed2.v);
        checksum = checksum + (x[0] + x[1] + x[2] + l[0] + l[1] + l[2]) * zero;
    }
    let mut summary = IntegrationSummary {
        max_speed2: max_speed2.to_array().into_iter().fold(0.0, f64::max),
        checksum: checksum.to_array().into_iter().sum(),
    };
    for i in whole..n {
        integrate_voxel(&mut st, i, dt, &mut summary);
    }
    summary
}

/// `[f(0), f(1), f(2)]`, written out: `array::map` is left to the optimizer's judgement, and
/// where it was not inlined its closures lost the vector instructions.
#[inline(always)]
fn three<T>(f: impl Fn(usize) -> T) -> [T; 3] {
    [f(0), f(1), f(2)]
}

/// [`three`] for four.
#[inline(always)]
fn four<T>(f: impl Fn(usize) -> T) -> [T; 4] {
    [f(0), f(1), f(2), f(3)]
}

/// One voxel, the scalar formula the lanes follow.
#[inline(always)]
fn integrate_voxel(s: &mut VoxelState, i: usize, dt: f64, summary: &mut IntegrationSummary) {
    let p = s.momentum[i] + s.force[i] * dt;
    s.momentum[i] = p;
    let v = p * s.inv_mass[i];
    s.velocity[i] = v;
    let x = s.position[i] + v * dt;
    s.position[i] = x;
    let l = s.angular_momentum[i] + s.torque[i] * dt;
    s.angular_momentum[i] = l;
    let w = l * s.inv_inertia[i];
    s.angular_velocity[i] = w;
    let q = s.orientation[i];
    // q̇ = ½ ω q (ω in the world frame), then back onto the unit sphere.
    let dq = Quat {
        w: 0.0,
        x: w.x,
        y: w.y,
        z: w.z,
    }
    .compose(q);
    let half_dt = 0.5 * dt;
    s.orientation[i] = Quat {
        w: q.w + half_dt * dq.w,
        x: q.x + half_dt * dq.x,
        y: q.y + half_dt * dq.y,
        z: q.z + half_dt * dq.z,
    }
    .normalized();
    s.force[i] = Vec3::ZERO;
    s.torque[i] = Vec3::ZERO;
    summary.max_speed2 = summary.max_speed2.max(v.norm2());
    summary.checksum += (x.x + x.y + x.z + l.x + l.y + l.z) * 0.0;
}

#[cfg(test)]
mod tests;
