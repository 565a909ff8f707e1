//! What a link pass is given and where it reads and writes, for both precisions of the kernel:
//! its inputs ([`LinkStep`], [`Job`], [`LinkConstants`]), the voxels' state gathered into lanes
//! ([`Source`], [`Ends`]), and the loads scattered onto the voxels in link order ([`Scatter`]) or
//! stored per link for a parallel pass ([`Store`], [`LinkLoads`]).

use super::lanes::{Arith, LANES, Lanes, Regroup, load_columns4, load_image3, store_image3};
use super::link_frame::{V3, gather_quat};
use super::math::{Quat, Vec3};
use super::state::Links;

/// Per-step inputs of the link pass.
#[derive(Clone, Copy, Debug)]
pub struct LinkStep {
    /// Voxel size s, m (the rest length of a passive link).
    pub voxel_size: f64,
    /// Linear rest-length factor λ(t) of actuated material (1 when not actuating).
    pub actuation_factor: f64,
}

/// What one run of the kernel reads and where it writes: the links' ends and axes, their
/// constants and the voxels' state in the kernel's precision `E`.
pub(super) struct Job<'a, S, E, O> {
    pub(super) links: &'a Links,
    pub(super) constants: LinkConstants<'a, E>,
    pub(super) source: S,
    pub(super) range: std::ops::Range<usize>,
    pub(super) step: LinkStep,
    pub(super) out: O,
}

impl<'a, O> Job<'a, VoxelView<'a>, f64, O> {
    pub(super) fn double(
        links: &'a Links,
        source: VoxelView<'a>,
        range: std::ops::Range<usize>,
        step: LinkStep,
        out: O,
    ) -> Self {
        Self {
            links,
            constants: LinkConstants {
                axial: &links.axial,
                shear: &links.shear,
                torsion: &links.torsion,
                bending: &links.bending,
                damping_time: &links.damping_time,
                actuated_fraction: &links.actuated_fraction,
            },
            source,
            range,
            step,
            out,
        }
    }
}

/// The per-link constants the kernel reads (see [`Links`]), in its precision.
#[derive(Clone, Copy)]
pub(super) struct LinkConstants<'a, E> {
    pub(super) axial: &'a [E],
    pub(super) shear: &'a [E],
    pub(super) torsion: &'a [E],
    pub(super) bending: &'a [E],
    pub(super) damping_time: &'a [E],
    pub(super) actuated_fraction: &'a [E],
}

/// Per-link results of [`super::link::link_loads`], one slot per link of its range.
#[derive(Debug)]
pub struct LinkLoads<'a> {
    pub force_b: &'a mut [Vec3],
    pub moment_a: &'a mut [Vec3],
    pub moment_b: &'a mut [Vec3],
}

/// One group of links as the kernel read it: lane j is link `k0 + j` and joins the voxels
/// `ends[j]` (a, b, axis); `count` lanes are real; `run` when they join consecutive voxels to
/// consecutive voxels.
#[derive(Clone, Copy)]
pub(super) struct Group<'a, const L: usize> {
    pub(super) k0: usize,
    pub(super) count: usize,
    pub(super) ends: &'a [(usize, usize, u8); L],
    pub(super) run: bool,
}

/// A group's results: the force on each link's b end (its a end gets the opposite) and the
/// moments on either end.
#[derive(Clone, Copy)]
pub(super) struct Loads<A: Arith<L>, const L: usize> {
    pub(super) f_b: V3<A, L>,
    pub(super) m_a: V3<A, L>,
    pub(super) m_b: V3<A, L>,
}

/// Where the kernel puts the results of a group of four links in `f64`.
pub(super) trait LinkOut {
    /// Cuts per-voxel outputs to the voxel count, so that the check of an index into the state
    /// also covers them (without it the kernel was 5 % slower).
    fn cut_to(&mut self, _voxels: usize) {}

    fn put<A: Regroup>(&mut self, group: Group<LANES>, loads: Loads<A, LANES>);
}

/// A kernel's arithmetic, with the way its results reach a [`LinkOut`].
pub(super) trait Kernel<const L: usize>: Arith<L> {
    /// Hands a group's results to `out`, four `f64` lanes at a time in link order.
    fn put<O: LinkOut>(self, out: &mut O, group: Group<L>, loads: Loads<Self, L>);
}

impl<A: Regroup> Kernel<LANES> for A {
    #[inline(always)]
    fn put<O: LinkOut>(self, out: &mut O, group: Group<LANES>, loads: Loads<Self, LANES>) {
        out.put(group, loads);
    }
}

/// Adds each link's forces and moments to its voxels, link by link in link order.
pub(super) struct Scatter<'a> {
    pub(super) force: &'a mut [Vec3],
    pub(super) torque: &'a mut [Vec3],
}

impl LinkOut for Scatter<'_> {
    #[inline(always)]
    fn cut_to(&mut self, voxels: usize) {
        self.force = &mut std::mem::take(&mut self.force)[..voxels];
        self.torque = &mut std::mem::take(&mut self.torque)[..voxels];
    }

    #[inline(always)]
    fn put<A: Regroup>(&mut self, group: Group<LANES>, loads: Loads<A, LANES>) {
        let (force, torque) = (&mut *self.force, &mut *self.torque);
        let Loads { f_b, m_a, m_b } = loads;
        if group.run {
            // Each voxel still sums in link order: a voxel that ends one link of the run as b
            // and a later one as a gets the earlier link's force first.
            let (a0, b0) = (group.ends[0].0, group.ends[0].1);
            let block = |i0: usize| i0..i0 + LANES;
            f_b.add_to::<false>(&mut force[block(b0)]);
            f_b.add_to::<true>(&mut force[block(a0)]);
            m_b.add_to::<false>(&mut torque[block(b0)]);
            m_a.add_to::<false>(&mut torque[block(a0)]);
        } else {
            let (f_b, m_a, m_b) = (f_b.lanes(), m_a.lanes(), m_b.lanes());
            for (j, &(ia, ib, _)) in group.ends.iter().enumerate().take(group.count) {
                force[ib] += f_b[j];
                force[ia] -= f_b[j];
                torque[ia] += m_a[j];
                torque[ib] += m_b[j];
            }
        }
    }
}

/// Stores each link's results in its slot of [`LinkLoads`] (slot 0 is link `first`).
pub(super) struct Store<'a> {
    pub(super) first: usize,
    pub(super) loads: LinkLoads<'a>,
}

impl LinkOut for Store<'_> {
    #[inline(always)]
    fn put<A: Regroup>(&mut self, group: Group<LANES>, loads: Loads<A, LANES>) {
        let (k0, count) = (group.k0, group.count);
        let slots = k0 - self.first..k0 - self.first + count;
        let l = &mut self.loads;
        for (v, out) in [
            (loads.f_b, &mut *l.force_b),
            (loads.m_a, &mut *l.moment_a),
            (loads.m_b, &mut *l.moment_b),
        ] {
            let out = &mut out[slots.clone()];
            if count == LANES {
                let arith = v.x.arith;
                store_image3(arith, out, arith.image3([v.x.v, v.y.v, v.z.v]));
            } else {
                out.copy_from_slice(&v.lanes()[..count]);
            }
        }
    }
}

/// Where the kernel reads a group's voxel state: the voxels' own `f64` arrays ([`VoxelView`]) or
/// their `f32` copy ([`SingleView`]).
pub(super) trait Source<A: Arith<L>, const L: usize>: Copy {
    /// The number of voxels.
    fn len(&self) -> usize;
    /// The same state with every array cut to [`Source::len`], so that one check of an index
    /// covers all of them (done inside the vectorized function, where it counts).
    fn cut(self) -> Self;
    /// Lane `j` joins voxel `ends[j].0` to voxel `ends[j].1`.
    fn gather<const DAMPED: bool>(&self, arith: A, ends: &[(usize, usize, u8); L]) -> Ends<A, L>;
    /// Lane `j` joins voxel `a0 + j` to voxel `b0 + j` (a run): the same values as
    /// [`Source::gather`], read as whole blocks.
    fn gather_run<const DAMPED: bool>(&self, arith: A, a0: usize, b0: usize) -> Ends<A, L>;
}

/// The voxel state the link kernel reads, cut to one length so that one check of an index covers
/// every array (or to one block of [`LANES`] voxels, see [`VoxelView::block`]).
#[derive(Clone, Copy)]
pub(super) struct VoxelView<'a> {
    pub(super) position: &'a [Vec3],
    pub(super) orientation: &'a [Quat],
    pub(super) velocity: &'a [Vec3],
    pub(super) angular_velocity: &'a [Vec3],
}

impl<'a> VoxelView<'a> {
    /// Voxels `i0..i0 + LANES`: read through it, lane `j` is voxel `i0 + j`.
    #[inline(always)]
    pub(super) fn block(&self, i0: usize) -> Self {
        self.block_at(i0, LANES)
    }

    /// Voxels `i0..i0 + len`.
    #[inline(always)]
    pub(super) fn block_at(&self, i0: usize, len: usize) -> Self {
        let r = i0..i0 + len;
        Self {
            position: &self.position[r.clone()],
            orientation: &self.orientation[r.clone()],
            velocity: &self.velocity[r.clone()],
            angular_velocity: &self.angular_velocity[r],
        }
    }
}

impl<A: Regroup> Source<A, LANES> for VoxelView<'_> {
    #[inline(always)]
    fn len(&self) -> usize {
        self.position.len()
    }

    #[inline(always)]
    fn cut(self) -> Self {
        self.block_at(0, self.position.len())
    }

    #[inline(always)]
    fn gather<const DAMPED: bool>(
        &self,
        arith: A,
        ends: &[(usize, usize, u8); LANES],
    ) -> Ends<A, LANES> {
        Ends::gather::<DAMPED>(arith, *self, |j| ends[j].0, *self, |j| ends[j].1)
    }

    #[inline(always)]
    fn gather_run<const DAMPED: bool>(&self, arith: A, a0: usize, b0: usize) -> Ends<A, LANES> {
        Ends::gather_run::<DAMPED>(arith, self.block(a0), self.block(b0))
    }
}

/// What the kernel reads of one group of links' two ends, one link per lane.
pub(super) struct Ends<A: Arith<L>, const L: usize> {
    pub(super) qa: [Lanes<A, L>; 4],
    pub(super) qb: [Lanes<A, L>; 4],
    /// x_b − x_a, world frame.
    pub(super) r: V3<A, L>,
    /// Velocities and spins of both ends (read only when the pass is damped).
    pub(super) va: V3<A, L>,
    pub(super) vb: V3<A, L>,
    pub(super) wa: V3<A, L>,
    pub(super) wb: V3<A, L>,
}

impl<A: Regroup> Ends<A, LANES> {
    /// Lane `j` joins voxel `ia(j)` of `a` to voxel `ib(j)` of `b`.
    #[inline(always)]
    pub(super) fn gather<const DAMPED: bool>(
        arith: A,
        a: VoxelView,
        ia: impl Fn(usize) -> usize,
        b: VoxelView,
        ib: impl Fn(usize) -> usize,
    ) -> Self {
        let zero = V3::splat(arith, 0.0);
        let (mut va, mut vb, mut wa, mut wb) = (zero, zero, zero, zero);
        if DAMPED {
            va = V3::gather(arith, |j| a.velocity[ia(j)]);
            vb = V3::gather(arith, |j| b.velocity[ib(j)]);
            wa = V3::gather(arith, |j| a.angular_velocity[ia(j)]);
            wb = V3::gather(arith, |j| b.angular_velocity[ib(j)]);
        }
        Self {
            qa: gather_quat(arith, a.orientation, &ia),
            qb: gather_quat(arith, b.orientation, &ib),
            r: V3::gather(arith, |j| b.position[ib(j)] - a.position[ia(j)]),
            va,
            vb,
            wa,
            wb,
        }
    }

    /// Links from the four voxels of block `a` to the four of block `b`, lane `j` from voxel
    /// `j` of each: whole-vector loads regrouped by component (the same values as
    /// [`Ends::gather`], in fewer instructions).
    #[inline(always)]
    pub(super) fn gather_run<const DAMPED: bool>(arith: A, a: VoxelView, b: VoxelView) -> Self {
        let zero = V3::splat(arith, 0.0);
        let (mut va, mut vb, mut wa, mut wb) = (zero, zero, zero, zero);
        if DAMPED {
            va = V3::block(arith, a.velocity);
            vb = V3::block(arith, b.velocity);
            wa = V3::block(arith, a.angular_velocity);
            wb = V3::block(arith, b.angular_velocity);
        }
        Self {
            qa: load_columns4(arith, a.orientation),
            qb: load_columns4(arith, b.orientation),
            r: {
                // x_b − x_a component by component in memory order, then regrouped.
                let (xa, xb) = (
                    load_image3(arith, a.position),
                    load_image3(arith, b.position),
                );
                let [x, y, z] = arith
                    .columns3(std::array::from_fn(|k| arith.sub(xb[k], xa[k])))
                    .map(|v| Lanes { v, arith });
                V3 { x, y, z }
            },
            va,
            vb,
            wa,
            wb,
        }
    }
}
