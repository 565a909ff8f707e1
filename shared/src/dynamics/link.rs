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

use super::lanes::{Arith, Element, LANES, Lanes, Portable, lane_array};
use super::link_ends::{
    Ends, Group, Job, Kernel, LinkOut, Loads, Scatter, Source, Store, VoxelView,
};
pub use super::link_ends::{LinkLoads, LinkStep};
use super::link_frame::{M3, SERIES_LIMIT, V3, axial_split, on_axis};
use super::math::Quat;
use super::single::SingleCopy;
use super::single_lanes::{SINGLE_LANES, Single};
use super::state::{Links, Voxels};

/// Adds every link's forces and moments to the voxels' accumulators. Returns the largest axial
/// strain |δ|/L seen, for divergence detection. `DAMPED` and `ACTUATED` select the variant at
/// compile time so a scene without link damping or actuation pays nothing for them.
///
/// Links go through the kernel [`LANES`] at a time: their voxels' state is gathered into lanes,
/// the kernel runs lane-wise (explicit AVX2 vectors where the CPU has them, see [`super::lanes`]),
/// and the forces and moments are added to the voxels one link at a time in link order, so every
/// voxel sums its contributions in the same order whatever the instruction set. The kernel uses
/// only IEEE additions, multiplications, divisions, square roots and selects (no fused
/// multiply-add), so the portable and the AVX2 copies of it give the same bits.
///
/// The kernel works in unshifted link-frame coordinates: the axis only picks, per lane, which
/// component gets the axial stiffness, the rest length and the torsion stiffness (the others get
/// shear and bending). In exact arithmetic it is the formula block at the top of this file:
/// - the mid rotation q_a(q_rel + 1) is q_a + |q_a|² q_b (sign-corrected), normalised through the
///   matrix with its exact norm;
/// - after the moment balance the coupling terms cancel: M_a = R(GJ/L·φx, EI/L·φy, EI/L·φz) + c,
///   M_b = −R(…) + c with c = ½ F_b × r, r = x_b − x_a in the world.
#[inline(never)]
pub fn link_pass<const DAMPED: bool, const ACTUATED: bool>(
    links: &Links,
    voxels: &mut Voxels,
    step: LinkStep,
) -> f64 {
    let (view, out) = scatter_into(voxels);
    let job = Job::double(links, view, 0..links.len(), step, out);
    dispatch::<Double, _, _, LANES, DAMPED, ACTUATED>(job)
}

/// [`link_pass`] in mixed precision: the kernel reads `single`'s `f32` copy of the state (which
/// must be this step's: written by the last integration or [`SingleCopy::copy_state`]) and its
/// `f32` link constants, computes in `f32` eight links at a time, and its forces and moments are
/// added to the `f64` accumulators link by link in link order, as [`link_pass`] adds its own (see
/// [`super::single`]).
#[inline(never)]
pub fn link_pass_mixed<const DAMPED: bool, const ACTUATED: bool>(
    links: &Links,
    single: &SingleCopy,
    voxels: &mut Voxels,
    step: LinkStep,
) -> f64 {
    let (_, out) = scatter_into(voxels);
    let job = single.job(links, 0..links.len(), step, out);
    dispatch::<Mixed, _, _, SINGLE_LANES, DAMPED, ACTUATED>(job)
}

/// The state the kernel reads and the accumulators it adds to, the borrows split and every array
/// cut to the voxel count (the kernel cuts them again inside, but without this cut too the
/// threaded pass's twin, `link_loads`, was 15 % slower).
pub(super) fn scatter_into(voxels: &mut Voxels) -> (VoxelView<'_>, Scatter<'_>) {
    let nv = voxels.len();
    let Voxels {
        position,
        orientation,
        velocity,
        angular_velocity,
        force,
        torque,
        ..
    } = voxels;
    let view = VoxelView {
        position: &position[..nv],
        orientation: &orientation[..nv],
        velocity: &velocity[..nv],
        angular_velocity: &angular_velocity[..nv],
    };
    let out = Scatter {
        force: &mut force[..nv],
        torque: &mut torque[..nv],
    };
    (view, out)
}

/// The forces and moments of links `range`, stored link by link instead of added to the voxels:
/// slot k − `range.start` of `loads` holds link k's force on its b end (the a end gets its
/// opposite) and its moments on either end. Returns the largest axial strain among them. Added to
/// the voxels in link order (`super::parallel`), they give the bits [`link_pass`] (or, with
/// `single`, [`link_pass_mixed`]) gives, so that threads can share the links of one step. A
/// `single` copy must be this step's, as for [`link_pass_mixed`].
pub fn link_loads<const DAMPED: bool, const ACTUATED: bool>(
    links: &Links,
    voxels: &Voxels,
    single: Option<&SingleCopy>,
    range: std::ops::Range<usize>,
    step: LinkStep,
    loads: LinkLoads,
) -> f64 {
    let out = Store {
        first: range.start,
        loads,
    };
    if let Some(single) = single {
        let job = single.job(links, range, step, out);
        return dispatch::<Mixed, _, _, SINGLE_LANES, DAMPED, ACTUATED>(job);
    }
    // Cut to the voxel count as `scatter_into` does (without it this pass was 15 % slower).
    let nv = voxels.len();
    let view = VoxelView {
        position: &voxels.position[..nv],
        orientation: &voxels.orientation[..nv],
        velocity: &voxels.velocity[..nv],
        angular_velocity: &voxels.angular_velocity[..nv],
    };
    let job = Job::double(links, view, range, step, out);
    dispatch::<Double, _, _, LANES, DAMPED, ACTUATED>(job)
}

/// A precision of the kernel: its tokens on either instruction set.
trait Precision<const L: usize> {
    /// Explicit AVX2 vectors.
    type Vector: Kernel<L>;
    /// Portable lanes, on any CPU.
    type Portable: Kernel<L, E = <Self::Vector as Arith<L>>::E>;
    fn vector(avx2: pulp::x86::V3) -> Self::Vector;
    const PORTABLE: Self::Portable;
}

/// Four `f64` lanes, reading the voxels' own state.
struct Double;

impl Precision<LANES> for Double {
    type Vector = pulp::x86::V3;
    type Portable = Portable;
    fn vector(avx2: pulp::x86::V3) -> Self::Vector {
        avx2
    }
    const PORTABLE: Portable = Portable;
}

/// Eight `f32` lanes, reading the state's `f32` copy.
struct Mixed;

impl Precision<SINGLE_LANES> for Mixed {
    type Vector = Single<pulp::x86::V3>;
    type Portable = Single<Portable>;
    fn vector(avx2: pulp::x86::V3) -> Self::Vector {
        Single(avx2)
    }
    const PORTABLE: Single<Portable> = Single(Portable);
}

/// Runs the kernel with explicit AVX2 vectors where the CPU has them, else on portable lanes.
#[inline(always)]
fn dispatch<P, S, O, const L: usize, const DAMPED: bool, const ACTUATED: bool>(
    job: Job<S, <P::Vector as Arith<L>>::E, O>,
) -> f64
where
    P: Precision<L>,
    S: Source<P::Vector, L> + Source<P::Portable, L>,
    O: LinkOut,
{
    #[cfg(target_arch = "x86_64")]
    if let Some(avx2) = pulp::x86::V3::try_new() {
        return pulp::Simd::vectorize(
            avx2,
            LinkPass::<_, S, O, L, DAMPED, ACTUATED> {
                arith: P::vector(avx2),
                job: &mut Some(job),
            },
        );
    }
    link_pass_lanes::<_, S, O, L, DAMPED, ACTUATED, true>(P::PORTABLE, job)
}

/// The kernel as a `pulp` operation, so that it is compiled with the instruction set of its
/// arithmetic enabled. The job goes by reference and is moved out inside: `pulp` passes an
/// operation of more than eight words another way, which lost the inlined vector code, and a
/// kernel that reached its slices through a reference reloaded them at every use (together 1.7
/// times slower).
struct LinkPass<'a, 'b, A: Arith<L>, S, O, const L: usize, const DAMPED: bool, const ACTUATED: bool>
{
    arith: A,
    job: &'a mut Option<Job<'b, S, A::E, O>>,
}

impl<A, S, O, const L: usize, const DAMPED: bool, const ACTUATED: bool> pulp::WithSimd
    for LinkPass<'_, '_, A, S, O, L, DAMPED, ACTUATED>
where
    A: Kernel<L>,
    S: Source<A, L>,
    O: LinkOut,
{
    type Output = f64;

    #[inline(always)]
    fn with_simd<Sd: pulp::Simd>(self, _simd: Sd) -> f64 {
        let job = self.job.take().expect("the job is set before the dispatch");
        link_pass_lanes::<A, S, O, L, DAMPED, ACTUATED, true>(self.arith, job)
    }
}

/// `RUNS` false reads every group through the general gather (for the test that the two agree).
#[inline(always)]
pub(super) fn link_pass_lanes<
    A: Kernel<L>,
    S: Source<A, L>,
    O: LinkOut,
    const L: usize,
    const DAMPED: bool,
    const ACTUATED: bool,
    const RUNS: bool,
>(
    arith: A,
    job: Job<S, A::E, O>,
) -> f64 {
    let Job {
        links,
        constants,
        source,
        range,
        step,
        mut out,
    } = job;
    // Every voxel array cut to one length here, inside the vectorized function: lengths that
    // arrive through `pulp`'s call are unrelated to the optimizer, and each access was checked.
    let source = source.cut();
    out.cut_to(source.len());
    let s = step.voxel_size;
    let stretch = step.actuation_factor - 1.0;
    let n = links.len();
    let splat = |x: f64| Lanes::splat(arith, x);
    let mut max_strain = splat(0.0);
    let (end_a, end_b, link_axis) = (&links.a[..n], &links.b[..n], &links.axis[..n]);
    // Known to the optimizer as at most n, so that a whole group's loads need no check.
    let end = range.end.min(n);
    let mut k0 = range.start;
    while k0 < end {
        let count = L.min(end - k0);
        // Lane j holds link k0 + j; past the end, copies of the last link (not scattered).
        let link = |j: usize| {
            let k = (k0 + j).min(n - 1);
            (end_a[k] as usize, end_b[k] as usize, link_axis[k])
        };
        let ends: [(usize, usize, u8); L] = lane_array(link);
        // A run: L consecutive voxels linked to L consecutive voxels (the links are in
        // axis-major grid order, so this is every group inside a solid stretch of the body).
        let (a0, b0) = (ends[0].0, ends[0].1);
        let run = RUNS && count == L && (1..L).all(|j| ends[j].0 == a0 + j && ends[j].1 == b0 + j);
        let axis = Lanes::from_fn(arith, |j| A::E::of(f64::from(ends[j].2)));
        let g = if run {
            source.gather_run::<DAMPED>(arith, a0, b0)
        } else {
            source.gather::<DAMPED>(arith, &ends)
        };
        let Ends {
            qa,
            qb,
            r,
            va,
            vb,
            wa,
            wb,
        } = g;
        // q_a* q_b, then the sign that puts it in the w ≥ 0 hemisphere.
        let [aw, ax, ay, az] = qa;
        let [bw, bx, by, bz] = qb;
        let rel_w = aw * bw + ax * bx + ay * by + az * bz;
        let rel = V3 {
            x: aw * bx - ax * bw - ay * bz + az * by,
            y: aw * by + ax * bz - ay * bw - az * bx,
            z: aw * bz - ax * by + ay * bx - az * bw,
        };
        let (minus, plus) = (splat(-1.0), splat(1.0));
        let sign = Lanes {
            v: arith.select_negative(rel_w.v, minus.v, plus.v),
            arith,
        };
        let w = rel_w * sign;
        // Mid frame: q_a (q_rel + 1) = q_a + sign |q_a|² q_b, normalised in the matrix.
        let na = aw * aw + ax * ax + ay * ay + az * az;
        let t = sign * na;
        let mid = [aw + t * bw, ax + t * bx, ay + t * by, az + t * bz];
        let mid_norm2 = mid[0] * mid[0] + mid[1] * mid[1] + mid[2] * mid[2] + mid[3] * mid[3];
        let frame = M3::from_quat(mid, splat(2.0) / mid_norm2);
        let d = frame.apply_transpose(r);

        // Rotation vector of sign · q_rel: 2 atan(|v|/w) v/|v|, a series below ~6°
        // (see [`Quat::rotation_vector`]), atan2 in the lanes above (in `f64` whatever the
        // lanes' precision, so that one `atan2` serves both).
        let s2 = rel.dot(rel);
        let inv_w = splat(1.0) / w;
        let t2 = s2 * inv_w * inv_w;
        let series = splat(1.0) - t2 * (splat(1.0 / 3.0) - t2 * (splat(0.2) - t2 * (1.0 / 7.0)));
        let mut phi_scale = inv_w * series * 2.0;
        // One test per lane, in the lanes' type, whichever way it is made: a lane's result must
        // not depend on the lanes beside it (threads cut the links at other places).
        let limit = A::E::of(SERIES_LIMIT);
        if !arith.all_below(t2.v, limit) {
            let t2 = t2.to_array();
            let (scale, s2, w) = (phi_scale.to_array(), s2.to_array(), w.to_array());
            phi_scale = Lanes::from_fn(arith, |j| {
                if t2[j] < limit {
                    scale[j]
                } else {
                    let sv = s2[j].wide().sqrt();
                    A::E::of(2.0 * sv.atan2(w[j].wide()) / sv)
                }
            });
        }
        let phi = rel.scale(phi_scale * sign);

        let rest = if ACTUATED {
            (Lanes::load(arith, constants.actuated_fraction, k0) * stretch + splat(1.0)) * s
        } else {
            splat(s)
        };
        let zero = splat(0.0);
        // d minus the rest length on the link axis; its axial component is the elongation δ.
        let mut e = d - axial_split(axis, rest, zero);
        let delta = on_axis(axis, 0.0, e.x, on_axis(axis, 1.0, e.y, e.z));
        max_strain.v = arith.max_abs(max_strain.v, delta.v);

        // Generalised deformation: the elastic one, plus β times its rate when damped
        // (stiffness-proportional damping through the same element, so it dissipates, leaves
        // rigid motion alone and balances its moments exactly like the elastic forces).
        let mut p = phi;
        if DAMPED {
            // Rate of d in the link frame, which turns with the mean spin of the pair.
            let spin = (wa + wb).scale(splat(0.5));
            let v_rel = vb - va - spin.cross(r);
            let beta = Lanes::load(arith, constants.damping_time, k0);
            e = e + frame.apply_transpose(v_rel).scale(beta);
            p = p + frame.apply_transpose(wb - wa).scale(beta);
        }

        // Stiffness per frame component: axial (EA/L) and torsion (GJ/L) on the link axis,
        // shear (12EI/L³) and bending (EI/L) across it.
        let k_e = axial_split(
            axis,
            Lanes::load(arith, constants.axial, k0),
            Lanes::load(arith, constants.shear, k0),
        );
        let k_p = axial_split(
            axis,
            Lanes::load(arith, constants.torsion, k0),
            Lanes::load(arith, constants.bending, k0),
        );
        let f_b = frame.apply(V3 {
            x: -(k_e.x * e.x),
            y: -(k_e.y * e.y),
            z: -(k_e.z * e.z),
        });
        let m_sym = frame.apply(V3 {
            x: k_p.x * p.x,
            y: k_p.y * p.y,
            z: k_p.z * p.z,
        });
        let c = f_b.cross(r).scale(splat(0.5));
        let m_a = m_sym + c;
        let m_b = c - m_sym;

        let group = Group {
            k0,
            count,
            ends: &ends,
            run,
        };
        arith.put(&mut out, group, Loads { f_b, m_a, m_b });
        k0 += L;
    }
    max_strain
        .to_array()
        .iter()
        .fold(0.0, |m: f64, &x| m.max(x.wide()))
        * (1.0 / s)
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
        let rest = links.rest_length(k, s, stretch);
        let delta = d.x - rest;
        energy += 0.5
            * (links.axial[k] * delta * delta
                + links.shear[k] * (d.y * d.y + d.z * d.z)
                + links.bending[k] * (phi.y * phi.y + phi.z * phi.z)
                + links.torsion[k] * phi.x * phi.x);
    }
    energy
}

#[cfg(test)]
pub(super) mod tests;
