//! The link damping integrated implicitly (issue 14, `damping.link_integration = "implicit"`).
//!
//! Explicit velocity damping bounds the step: symplectic Euler needs h² + 4ζh ≤ 4 at the lattice's
//! top mode (h = ω_top·dt), so ζ = 1 allows f ≈ 1.44 where the stiffness alone allows f ≈ 3.5
//! (docs/dynamics.md, "Open points"). Here the step is split: the momenta take the elastic and
//! every other force (kick), the link damping then acts on the new velocities as backward Euler,
//! and only then do positions and orientations move (drift). Backward Euler of a dissipation is a
//! contraction, so the damping no longer bounds the step, and the stiffness's own bound is met
//! whatever ζ is.
//!
//! The damping is the explicit pass's, a quadratic dissipation per link. With the pair's rates
//! g = (v_rel, ω_rel), v_rel = v_b − v_a − ½(ω_a + ω_b) × r, ω_rel = ω_b − ω_a, it is
//! D = ½β(k_t |v_rel|² + ω_relᵀ K_r ω_rel), k_t = EA/L = 12EI/L³ (equal for a cube link),
//! K_r = EI/L on the bending axes and GJ/L about the link axis of the mid frame, and its forces,
//! −∂D/∂u, are exactly what the explicit link pass adds. Backward Euler on the whole lattice is a
//! linear solve; it is taken one link at a time instead (a Gauss–Seidel sweep in link order,
//! deterministic): each link's pair gets the exact backward-Euler step of its own dissipation,
//! u' = u − M⁻¹Jᵀp with (J M⁻¹ Jᵀ + (dt β K)⁻¹) p = J u, a 6×6 positive-definite solve. Each such
//! step conserves the pair's linear and angular momentum (the impulses are a link's forces) and
//! never adds kinetic energy, so neither does the sweep; to first order in dt it is the explicit
//! damping, so slow modes are damped as before.

use super::math::{Quat, Vec3};
use super::state::{Links, Voxels};

/// Momenta and velocities from the step's forces and torques (the first half of symplectic
/// Euler), clearing the accumulators.
#[inline(never)]
pub fn kick_pass(voxels: &mut Voxels, dt: f64) {
    for i in 0..voxels.len() {
        let p = voxels.momentum[i] + voxels.force[i] * dt;
        voxels.momentum[i] = p;
        voxels.velocity[i] = p * voxels.inv_mass[i];
        let l = voxels.angular_momentum[i] + voxels.torque[i] * dt;
        voxels.angular_momentum[i] = l;
        voxels.angular_velocity[i] = l * voxels.inv_inertia[i];
        voxels.force[i] = Vec3::ZERO;
        voxels.torque[i] = Vec3::ZERO;
    }
}

/// Positions and orientations from the (damped) velocities: the second half of symplectic Euler,
/// the same formula as the fused integration. Returns the largest squared speed and the
/// non-finiteness checksum.
#[inline(never)]
pub fn drift_pass(voxels: &mut Voxels, dt: f64) -> (f64, f64) {
    let (mut max_speed2, mut checksum) = (0.0f64, 0.0);
    let half_dt = 0.5 * dt;
    for i in 0..voxels.len() {
        let v = voxels.velocity[i];
        let x = voxels.position[i] + v * dt;
        voxels.position[i] = x;
        let w = voxels.angular_velocity[i];
        let q = voxels.orientation[i];
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
        max_speed2 = max_speed2.max(v.norm2());
        let l = voxels.angular_momentum[i];
        checksum += x.x + x.y + x.z + l.x + l.y + l.z;
    }
    (max_speed2, checksum)
}

/// The sweep's constants for a time step dt: what each link's 6×6 system S = J M⁻¹ Jᵀ + (dt β K)⁻¹
/// holds that does not depend on the state.
#[derive(Clone, Debug, Default)]
pub struct ImplicitDamping {
    dt: f64,
    links: Vec<LinkConstants>,
}

/// S's translational block is c_t I − σ r rᵀ with c_t = c₀ + σ|r|², its rotational block
/// c_r I + d n nᵀ (n the link axis of the mid frame), and they are coupled by
/// ½(1/I_b − 1/I_a)[r]×, which vanishes between voxels of equal inertia (the common case: each
/// block then inverts in closed form, Sherman–Morrison; both denominators are sums of positive
/// terms).
#[derive(Clone, Copy, Debug, PartialEq)]
struct LinkConstants {
    /// σ = ¼(1/I_a + 1/I_b).
    spin: f64,
    /// c₀ = 1/m_a + 1/m_b + 1/(dt β EA/L).
    c0: f64,
    /// 1/c_r, c_r = 1/I_a + 1/I_b + 1/(dt β EI/L).
    inv_c_r: f64,
    /// d/(c_r + d), d = 1/(dt β GJ/L) − 1/(dt β EI/L).
    d_ratio: f64,
    /// Whether the closed form holds (equal inertia, and EA/L = 12EI/L³ as for every cube link
    /// unless the Poisson coupling stiffened it) and whether the link is damped at all.
    closed_form: bool,
    damped: bool,
}

impl LinkConstants {
    fn new(pair: &Pair) -> Self {
        let [ma, mb] = pair.inv_mass;
        let [ia, ib] = pair.inv_inertia;
        let (bend, twist) = (1.0 / pair.h_bending, 1.0 / pair.h_torsion);
        let c_r = ia + ib + bend;
        let d = twist - bend;
        Self {
            spin: 0.25 * (ia + ib),
            c0: ma + mb + 1.0 / pair.h_translational,
            inv_c_r: 1.0 / c_r,
            d_ratio: d / (c_r + d),
            closed_form: ia == ib
                && (pair.h_translational - pair.h_shear).abs() <= 1e-12 * pair.h_translational,
            damped: pair.h_translational > 0.0,
        }
    }

    /// The impulse for voxels of equal inertia.
    #[inline(always)]
    fn impulse(&self, r: Vec3, n: Vec3, v_rel: Vec3, w_rel: Vec3) -> (Vec3, Vec3) {
        let r2 = r.norm2();
        let inv_c_t = 1.0 / (self.c0 + self.spin * r2);
        let pv = (v_rel + r * (self.spin * r.dot(v_rel) / self.c0)) * inv_c_t;
        let pw = (w_rel - n * (self.d_ratio * n.dot(w_rel))) * self.inv_c_r;
        (pv, pw)
    }
}

impl ImplicitDamping {
    pub fn new(links: &Links, voxels: &Voxels, dt: f64) -> Self {
        // Backward Euler. (The trapezoidal rule, backward Euler over half the step and twice its
        // impulse, is second order but leaves the top modes undamped at long steps: measured
        // worse at f = 2.5, docs/dynamics.md.)
        let links = (0..links.len())
            .map(|k| LinkConstants::new(&Pair::at_rest(links, voxels, k, dt)))
            .collect();
        Self { dt, links }
    }

    /// The backward-Euler link damping, one link at a time in link order. `held` voxels (static
    /// friction holding them on the floor) get their tangential velocity cancelled again
    /// afterwards, as the floor pass cancelled it before the kick.
    #[inline(never)]
    pub fn pass(&self, links: &Links, voxels: &mut Voxels, held: &[bool]) {
        for (k, c) in self.links.iter().enumerate() {
            if c.damped {
                self.damp_pair(links, voxels, k, c);
            }
        }
        for (i, &held) in held.iter().enumerate() {
            if held {
                let (v, p) = (&mut voxels.velocity[i], &mut voxels.momentum[i]);
                (v.x, v.y, p.x, p.y) = (0.0, 0.0, 0.0, 0.0);
            }
        }
    }

    /// The exact backward-Euler step of link `k`'s dissipation on its pair.
    #[inline(always)]
    fn damp_pair(&self, links: &Links, voxels: &mut Voxels, k: usize, c: &LinkConstants) {
        let (a, b) = (links.a[k] as usize, links.b[k] as usize);
        let v = &voxels;
        let r = v.position[b] - v.position[a];
        let (wa, wb) = (v.angular_velocity[a], v.angular_velocity[b]);
        let n = mid_axis(v.orientation[a], v.orientation[b], links.axis[k]);
        let v_rel = v.velocity[b] - v.velocity[a] + r.cross(wa + wb) * 0.5;
        let w_rel = wb - wa;
        let (pv, pw) = if c.closed_form {
            c.impulse(r, n, v_rel, w_rel)
        } else {
            let mut pair = Pair::at_rest(links, voxels, k, self.dt);
            (pair.r, pair.n, pair.v_rel, pair.w_rel) = (r, n, v_rel, w_rel);
            pair.solve()
        };
        let (ma, mb) = (v.inv_mass[a], v.inv_mass[b]);
        let (ia, ib) = (v.inv_inertia[a], v.inv_inertia[b]);
        // u' = u − M⁻¹Jᵀp: +p_v on a's momentum and −p_v on b's (a link force's impulse), and
        // the moments ½ r × p_v ± p_ω that keep the pair's angular momentum.
        let half_r_cross = r.cross(pv) * 0.5;
        let (la, lb) = (half_r_cross + pw, half_r_cross - pw);
        voxels.velocity[a] += pv * ma;
        voxels.velocity[b] -= pv * mb;
        voxels.angular_velocity[a] += la * ia;
        voxels.angular_velocity[b] += lb * ib;
        voxels.momentum[a] += pv;
        voxels.momentum[b] -= pv;
        voxels.angular_momentum[a] += la;
        voxels.angular_momentum[b] += lb;
    }
}

/// The link axis (`axis` 0, 1, 2 for x, y, z) of the mid frame q_a (q_rel + 1), as the link
/// pass builds it: that column of the frame's rotation matrix.
#[inline(always)]
fn mid_axis(qa: Quat, qb: Quat, axis: u8) -> Vec3 {
    let rel_w = qa.w * qb.w + qa.x * qb.x + qa.y * qb.y + qa.z * qb.z;
    let t = if rel_w < 0.0 { -qa.norm2() } else { qa.norm2() };
    let (w, x, y, z) = (
        qa.w + t * qb.w,
        qa.x + t * qb.x,
        qa.y + t * qb.y,
        qa.z + t * qb.z,
    );
    let s = 2.0 / (w * w + x * x + y * y + z * z);
    match axis {
        0 => Vec3::new(
            1.0 - s * (y * y + z * z),
            s * (x * y + w * z),
            s * (x * z - w * y),
        ),
        1 => Vec3::new(
            s * (x * y - w * z),
            1.0 - s * (x * x + z * z),
            s * (y * z + w * x),
        ),
        _ => Vec3::new(
            s * (x * z + w * y),
            s * (y * z - w * x),
            1.0 - s * (x * x + y * y),
        ),
    }
}

/// What one link's backward-Euler damping step needs of its pair.
#[derive(Clone, Copy, Debug)]
struct Pair {
    /// x_b − x_a.
    r: Vec3,
    /// The link axis of the mid frame, a unit vector.
    n: Vec3,
    inv_mass: [f64; 2],
    inv_inertia: [f64; 2],
    /// The deformation rates: v_rel and ω_rel.
    v_rel: Vec3,
    w_rel: Vec3,
    /// dt·β times the link's stiffnesses: axial (EA/L), shear (12EI/L³), bending (EI/L),
    /// torsion (GJ/L).
    h_translational: f64,
    h_shear: f64,
    h_bending: f64,
    h_torsion: f64,
}

impl Pair {
    /// Link `k`'s pair with its constants for step `dt`, at rest along its axis.
    fn at_rest(links: &Links, voxels: &Voxels, k: usize, dt: f64) -> Self {
        let (a, b) = (links.a[k] as usize, links.b[k] as usize);
        let h = dt * links.damping_time[k];
        Self {
            r: Vec3::ZERO,
            n: Vec3::ZERO,
            inv_mass: [voxels.inv_mass[a], voxels.inv_mass[b]],
            inv_inertia: [voxels.inv_inertia[a], voxels.inv_inertia[b]],
            v_rel: Vec3::ZERO,
            w_rel: Vec3::ZERO,
            h_translational: h * links.axial[k],
            h_shear: h * links.shear[k],
            h_bending: h * links.bending[k],
            h_torsion: h * links.torsion[k],
        }
    }

    /// The impulse p = (p_v, p_ω) solving (J M⁻¹ Jᵀ + (h K)⁻¹) p = (v_rel, ω_rel) by a 6×6
    /// Cholesky factorisation, for any pair.
    fn solve(&self) -> (Vec3, Vec3) {
        let Self { r, n, .. } = *self;
        let [ia, ib] = self.inv_inertia;
        let c = LinkConstants::new(self);
        // Translational: (h K_t)⁻¹ = I/(h k_shear) + (1/(h k_axial) − 1/(h k_shear)) n nᵀ.
        let c_t = c.c0 - 1.0 / self.h_translational + 1.0 / self.h_shear + c.spin * r.norm2();
        let d_t = 1.0 / self.h_translational - 1.0 / self.h_shear;
        let (bend, twist) = (1.0 / self.h_bending, 1.0 / self.h_torsion);
        let (c_r, d) = (ia + ib + bend, twist - bend);
        let mut s = [[0.0f64; 6]; 6];
        let (rv, nv) = ([r.x, r.y, r.z], [n.x, n.y, n.z]);
        let coupling = 0.5 * (ib - ia);
        // [r]× as rows: [r]× x = r × x.
        let cross = [[0.0, -r.z, r.y], [r.z, 0.0, -r.x], [-r.y, r.x, 0.0]];
        for i in 0..3 {
            for j in 0..3 {
                let diagonal = if i == j { 1.0 } else { 0.0 };
                s[i][j] = c_t * diagonal - c.spin * rv[i] * rv[j] + d_t * nv[i] * nv[j];
                s[i][j + 3] = coupling * cross[i][j];
                s[j + 3][i] = s[i][j + 3];
                s[i + 3][j + 3] = c_r * diagonal + d * nv[i] * nv[j];
            }
        }
        let (v, w) = (self.v_rel, self.w_rel);
        let p = solve_spd(&mut s, [v.x, v.y, v.z, w.x, w.y, w.z]);
        (Vec3::new(p[0], p[1], p[2]), Vec3::new(p[3], p[4], p[5]))
    }
}

/// Solves S x = rhs for a symmetric positive-definite 6×6 S by Cholesky (S is overwritten).
#[inline(always)]
#[allow(clippy::needless_range_loop)] // the factorisation reads as its index formulas
fn solve_spd(s: &mut [[f64; 6]; 6], rhs: [f64; 6]) -> [f64; 6] {
    for j in 0..6 {
        let mut d = s[j][j];
        for k in 0..j {
            d -= s[j][k] * s[j][k];
        }
        let d = d.sqrt();
        s[j][j] = d;
        for i in j + 1..6 {
            let mut x = s[i][j];
            for k in 0..j {
                x -= s[i][k] * s[j][k];
            }
            s[i][j] = x / d;
        }
    }
    let mut y = rhs;
    for i in 0..6 {
        for k in 0..i {
            y[i] -= s[i][k] * y[k];
        }
        y[i] /= s[i][i];
    }
    for i in (0..6).rev() {
        for k in i + 1..6 {
            y[i] -= s[k][i] * y[k];
        }
        y[i] /= s[i][i];
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::link::{LinkStep, link_pass};
    use crate::dynamics::state::build_state;
    use crate::material::{Material, MaterialId, Palette};
    use crate::voxel::{GridDims, VoxelGrid};

    const S: f64 = 0.01;

    /// A 3×3×2 block, slightly deformed and turned, moving and spinning every which way; with
    /// `mixed`, a denser and stiffer second material in some cells (voxels of unequal inertia,
    /// the general solve).
    fn moving_block(mixed: bool) -> (Voxels, Links) {
        let dims = GridDims::new(3, 3, 2);
        let mut grid = VoxelGrid::filled(dims, MaterialId(0));
        if mixed {
            for (x, y, z) in [(0, 0, 0), (1, 1, 0), (2, 1, 1), (1, 2, 1)] {
                grid.set(x, y, z, Some(MaterialId(1)));
            }
        }
        let mut dense = Material::new("dense", 5.0e6, 0.3);
        dense.density = 3000.0;
        let palette = Palette(vec![Material::new("soft", 1.0e6, 0.35), dense]);
        let (mut v, l) = build_state(&grid, &palette, S, 1.0).unwrap();
        for i in 0..v.len() {
            let t = i as f64;
            let wave =
                |a: f64, b: f64, c: f64| Vec3::new((a * t).sin(), (b * t).cos(), (c * t).sin());
            v.position[i] += wave(0.7, 1.3, 2.1) * (0.02 * S);
            v.orientation[i] = Quat::from_rotation_vector(wave(0.3, 0.5, 0.9) * 0.05);
            v.velocity[i] = wave(1.1, 0.2, 0.4) * 0.3;
            v.angular_velocity[i] = wave(0.6, 1.7, 0.8) * 40.0;
            v.momentum[i] = v.velocity[i] * v.mass[i];
            v.angular_momentum[i] = v.angular_velocity[i] * (1.0 / v.inv_inertia[i]);
        }
        (v, l)
    }

    fn momenta(v: &Voxels) -> (Vec3, Vec3) {
        let mut p = Vec3::ZERO;
        let mut l = Vec3::ZERO;
        for i in 0..v.len() {
            p += v.momentum[i];
            l += v.position[i].cross(v.momentum[i]) + v.angular_momentum[i];
        }
        (p, l)
    }

    fn kinetic(v: &Voxels) -> f64 {
        (0..v.len())
            .map(|i| {
                0.5 * v.mass[i] * v.velocity[i].norm2()
                    + 0.5 * v.angular_velocity[i].norm2() / v.inv_inertia[i]
            })
            .sum()
    }

    /// The closed form (voxels of equal inertia) is the 6×6 solve, to rounding.
    #[test]
    fn the_closed_form_and_the_general_solve_agree() {
        let pair = Pair {
            r: Vec3::new(0.0101, 0.0003, -0.0002),
            n: Quat::from_rotation_vector(Vec3::new(0.02, -0.05, 0.03))
                .rotate(Vec3::new(1.0, 0.0, 0.0)),
            inv_mass: [1.0e3, 1.0e3],
            inv_inertia: [6.0e7, 6.0e7],
            v_rel: Vec3::new(0.3, -0.1, 0.2),
            w_rel: Vec3::new(-20.0, 35.0, 5.0),
            h_translational: 0.7e-3,
            h_shear: 0.7e-3,
            h_bending: 0.7e-3 * 1e-4 / 12.0,
            h_torsion: 0.7e-3 * 1e-4 / 6.0 / 2.7,
        };
        let fast = LinkConstants::new(&pair).impulse(pair.r, pair.n, pair.v_rel, pair.w_rel);
        let general = pair.solve();
        for (a, b) in [(fast.0, general.0), (fast.1, general.1)] {
            assert!((a - b).norm() <= 1e-12 * b.norm(), "{a:?} vs {b:?}");
        }
    }

    /// A sweep moves momentum only between the two voxels of a link, as a link's forces do: the
    /// body's linear and angular momentum are unchanged to rounding, and it never adds kinetic
    /// energy, whatever the step (backward Euler of a dissipation).
    #[test]
    fn a_sweep_conserves_momentum_and_only_takes_energy() {
        for mixed in [false, true] {
            for dt in [1e-6, 1e-4, 1e-2] {
                let (mut v, l) = moving_block(mixed);
                let (p0, l0) = momenta(&v);
                let k0 = kinetic(&v);
                ImplicitDamping::new(&l, &v, dt).pass(&l, &mut v, &[]);
                let (p1, l1) = momenta(&v);
                let k1 = kinetic(&v);
                let scale_p: f64 = (0..v.len()).map(|i| v.mass[i] * 0.3).sum();
                assert!(
                    (p1 - p0).norm() <= 1e-13 * scale_p,
                    "{mixed} {dt}: {p0:?} {p1:?}"
                );
                assert!(
                    (l1 - l0).norm() <= 1e-13 * scale_p * 0.05,
                    "{mixed} {dt}: {l0:?} {l1:?}"
                );
                assert!(k1 < k0, "{mixed} {dt}: {k0} -> {k1}");
                for i in 0..v.len() {
                    let dv = v.velocity[i] - v.momentum[i] * v.inv_mass[i];
                    assert!(dv.norm() <= 1e-12 * v.velocity[i].norm().max(1e-9));
                }
            }
        }
    }

    /// For a short step the sweep is the explicit link damping: the velocity change over dt is the
    /// damping force the explicit link pass adds (its damped minus its undamped forces) over the
    /// mass, within O(dt·β·k/m); also for links whose axial stiffness the Poisson coupling
    /// raised above their shear stiffness (`stiffened`).
    #[test]
    fn a_short_step_damps_as_the_explicit_link_pass() {
        for (mixed, stiffened) in [(false, false), (true, false), (false, true)] {
            let (v0, mut l) = moving_block(mixed);
            if stiffened {
                l.axial.iter_mut().for_each(|k| *k *= 1.6);
            }
            let step = LinkStep {
                voxel_size: S,
                actuation_factor: 1.0,
            };
            let (mut damped, mut plain) = (v0.clone(), v0.clone());
            link_pass::<true, false>(&l, &mut damped, step);
            link_pass::<false, false>(&l, &mut plain, step);
            // ω_top·dt = 1e-4: the explicit and implicit steps differ by about that, relatively.
            let omega_top = (14.0 * 1.0e6 * S / (1000.0 * S * S * S)).sqrt();
            let dt = 1e-4 / omega_top;
            let mut v = v0.clone();
            ImplicitDamping::new(&l, &v, dt).pass(&l, &mut v, &[]);
            let (mut worst, mut largest) = (0.0f64, 0.0f64);
            for i in 0..v.len() {
                let explicit = (damped.force[i] - plain.force[i]) * (dt * v.inv_mass[i]);
                let implicit = v.velocity[i] - v0.velocity[i];
                worst = worst.max((explicit - implicit).norm());
                largest = largest.max(explicit.norm());
                let explicit_w = (damped.torque[i] - plain.torque[i]) * (dt * v.inv_inertia[i]);
                let implicit_w = v.angular_velocity[i] - v0.angular_velocity[i];
                assert!(
                    (explicit_w - implicit_w).norm() <= 1e-3 * explicit_w.norm().max(1e-12),
                    "{mixed}, voxel {i}: spin change {implicit_w:?}, explicit {explicit_w:?}"
                );
            }
            assert!(largest > 0.0);
            assert!(worst <= 1e-3 * largest, "{mixed}: {worst} of {largest}");
        }
    }

    /// A held voxel (static friction) keeps no tangential velocity through the sweep.
    #[test]
    fn a_held_voxel_stays_held() {
        let (mut v, l) = moving_block(false);
        let mut held = vec![false; v.len()];
        held[4] = true;
        ImplicitDamping::new(&l, &v, 1e-4).pass(&l, &mut v, &held);
        assert_eq!((v.velocity[4].x, v.velocity[4].y), (0.0, 0.0));
        assert_eq!((v.momentum[4].x, v.momentum[4].y), (0.0, 0.0));
        assert_ne!(v.velocity[3].x, 0.0);
    }
}
