//! The mixed-precision link kernel: the state stays `f64` and is integrated in `f64`, and the link
//! kernel reads an `f32` copy of it and computes in `f32`, eight links per 256-bit vector instead
//! of four.
//!
//! Why not an `f32` state: a voxel moves v·dt ≈ 10⁻⁹ m per step, and an `f32` position 16–32 mm
//! from the origin has a spacing of 1.9·10⁻⁹ m, so an `f32` integration would lose the motion. A
//! link only needs the difference of its two ends' positions, their orientations, and (damped)
//! their velocities and spins; rounding those to `f32` moves a random robot's gait 7–40 times
//! less than halving the time step does (docs/explanation/physics.md). The copy
//! holds positions relative to voxel 0 (`SingleCopy::copy_state`), so that a body far from the
//! origin loses no more than one near it: the kernel is translation-invariant to `f64` rounding.
//!
//! The kernel is the double-precision one ([`super::link`]) on other lanes: the same IEEE
//! operations in the same order, no fused multiply-add, so its AVX2 and portable copies give the
//! same bits, and each group's forces and moments are widened to `f64` (exact) and added to the
//! voxels four links at a time in link order, as the double kernel adds its own. So the result is
//! the same bits for any thread count and any x86-64 CPU, as before; it differs from the double
//! kernel's by the rounding measured in docs/explanation/physics.md.

use super::lanes::{Arith, LANES, Lanes, Portable, Regroup, load_columns3, load_columns4};
use super::link_ends::{Ends, Job, LinkConstants, LinkStep, Source};
use super::link_frame::V3;
use super::math::Vec3;
use super::single_lanes::{SINGLE_LANES, Widen, run_of_four};
use super::state::{Links, Voxels};

/// Components of the `f32` copy, one array each: position (relative to voxel 0), orientation,
/// velocity, spin.
const POSITION: usize = 0;
const ORIENTATION: usize = 3;
const VELOCITY: usize = 7;
const SPIN: usize = 10;
const COMPONENTS: usize = 13;

/// The `f32` copy of the state and link constants that the mixed-precision kernel reads.
#[derive(Clone, Debug)]
pub struct SingleCopy {
    /// One array per component (see [`POSITION`] …), one entry per voxel.
    state: [Vec<f32>; COMPONENTS],
    axial: Vec<f32>,
    shear: Vec<f32>,
    torsion: Vec<f32>,
    bending: Vec<f32>,
    damping_time: Vec<f32>,
    actuated_fraction: Vec<f32>,
}

impl SingleCopy {
    /// The copy for `voxels` voxels joined by `links` (its link constants rounded to `f32` once).
    pub fn new(links: &Links, voxels: usize) -> Self {
        let round = |x: &[f64]| x.iter().map(|&x| x as f32).collect();
        Self {
            state: std::array::from_fn(|_| vec![0.0; voxels]),
            axial: round(&links.axial),
            shear: round(&links.shear),
            torsion: round(&links.torsion),
            bending: round(&links.bending),
            damping_time: round(&links.damping_time),
            actuated_fraction: round(&links.actuated_fraction),
        }
    }

    /// Writes the copy from the voxels' state: what the kernel reads (velocities and spins only
    /// when `DAMPED`), positions relative to voxel 0's.
    pub fn copy_state<const DAMPED: bool>(&mut self, voxels: &Voxels) {
        let job = CopyJob {
            voxels,
            state: &mut self.state,
        };
        #[cfg(target_arch = "x86_64")]
        if let Some(avx2) = pulp::x86::V3::try_new() {
            return pulp::Simd::vectorize(
                avx2,
                CopyPass::<_, DAMPED> {
                    arith: avx2,
                    job: &mut Some(job),
                },
            );
        }
        copy_lanes::<_, DAMPED>(Portable, job);
    }

    /// A run of the kernel over links `range` on this copy, its results going to `out`.
    pub(super) fn job<'a, O>(
        &'a self,
        links: &'a Links,
        range: std::ops::Range<usize>,
        step: LinkStep,
        out: O,
    ) -> Job<'a, SingleView<'a>, f32, O> {
        Job {
            links,
            constants: LinkConstants {
                axial: &self.axial,
                shear: &self.shear,
                torsion: &self.torsion,
                bending: &self.bending,
                damping_time: &self.damping_time,
                actuated_fraction: &self.actuated_fraction,
            },
            source: SingleView {
                c: std::array::from_fn(|k| self.state[k].as_slice()),
            },
            range,
            step,
            out,
        }
    }
}

/// What the copy reads and writes.
struct CopyJob<'a> {
    voxels: &'a Voxels,
    state: &'a mut [Vec<f32>; COMPONENTS],
}

/// The copy as a `pulp` operation (see `link::LinkPass`).
struct CopyPass<'a, 'b, A, const DAMPED: bool> {
    arith: A,
    job: &'a mut Option<CopyJob<'b>>,
}

impl<A: Regroup, const DAMPED: bool> pulp::WithSimd for CopyPass<'_, '_, A, DAMPED> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let job = self.job.take().expect("the job is set before the dispatch");
        copy_lanes::<A, DAMPED>(self.arith, job);
    }
}

/// Four voxels at a time: each block's `f64` columns, rounded to `f32`.
#[inline(always)]
fn copy_lanes<A: Regroup, const DAMPED: bool>(arith: A, job: CopyJob) {
    let CopyJob { voxels, state } = job;
    let n = voxels.len();
    let (position, orientation) = (&voxels.position[..n], &voxels.orientation[..n]);
    let (velocity, spin) = (&voxels.velocity[..n], &voxels.angular_velocity[..n]);
    let mut out: [&mut [f32]; COMPONENTS] = state.each_mut().map(|c| &mut c[..n]);
    let origin = position.first().copied().unwrap_or(Vec3::ZERO);
    let o = [
        Lanes::splat(arith, origin.x),
        Lanes::splat(arith, origin.y),
        Lanes::splat(arith, origin.z),
    ];
    let whole = n - n % LANES;
    for i0 in (0..whole).step_by(LANES) {
        let r = i0..i0 + LANES;
        let [x, y, z] = load_columns3(arith, &position[r.clone()]);
        put(&mut out[POSITION][r.clone()], x - o[0]);
        put(&mut out[POSITION + 1][r.clone()], y - o[1]);
        put(&mut out[POSITION + 2][r.clone()], z - o[2]);
        let [w, x, y, z] = load_columns4(arith, &orientation[r.clone()]);
        put(&mut out[ORIENTATION][r.clone()], w);
        put(&mut out[ORIENTATION + 1][r.clone()], x);
        put(&mut out[ORIENTATION + 2][r.clone()], y);
        put(&mut out[ORIENTATION + 3][r.clone()], z);
        if DAMPED {
            for (k, block) in [(VELOCITY, velocity), (SPIN, spin)] {
                let [x, y, z] = load_columns3(arith, &block[r.clone()]);
                put(&mut out[k][r.clone()], x);
                put(&mut out[k + 1][r.clone()], y);
                put(&mut out[k + 2][r.clone()], z);
            }
        }
    }
    let take = if DAMPED { COMPONENTS } else { VELOCITY };
    for i in whole..n {
        let (p, q) = (position[i] - origin, orientation[i]);
        let (v, w) = (velocity[i], spin[i]);
        let values = [
            p.x, p.y, p.z, q.w, q.x, q.y, q.z, v.x, v.y, v.z, w.x, w.y, w.z,
        ];
        for (c, value) in out.iter_mut().zip(values).take(take) {
            c[i] = value as f32;
        }
    }
}

/// Four voxels' component `l`, rounded to `f32`, into `out` (a function, not a closure: a closure is
/// compiled without the vector instructions of the function around it).
#[inline(always)]
fn put<A: Regroup>(out: &mut [f32], l: Lanes<A, LANES>) {
    out.copy_from_slice(&l.arith.narrow(l.v));
}

/// The `f32` copy as the kernel reads it: one array per component, cut to the voxel count.
#[derive(Clone, Copy)]
pub(super) struct SingleView<'a> {
    c: [&'a [f32]; COMPONENTS],
}

/// How [`ends`] reads one end's components: lane by lane, or as whole blocks.
trait Read<A: Arith<SINGLE_LANES, E = f32>> {
    /// Component `k` of the eight voxels, one per lane.
    fn lanes(&self, arith: A, k: usize) -> Lanes<A, SINGLE_LANES>;

    /// Components `k..k + 3`.
    #[inline(always)]
    fn v3(&self, arith: A, k: usize) -> V3<A, SINGLE_LANES> {
        V3 {
            x: self.lanes(arith, k),
            y: self.lanes(arith, k + 1),
            z: self.lanes(arith, k + 2),
        }
    }

    /// The orientation (w, x, y, z).
    #[inline(always)]
    fn quat(&self, arith: A) -> [Lanes<A, SINGLE_LANES>; 4] {
        [
            self.lanes(arith, ORIENTATION),
            self.lanes(arith, ORIENTATION + 1),
            self.lanes(arith, ORIENTATION + 2),
            self.lanes(arith, ORIENTATION + 3),
        ]
    }
}

/// Voxels `i0..i0 + 8`, read as one vector per component.
struct Block<'a> {
    view: &'a SingleView<'a>,
    i0: usize,
}

impl<A: Arith<SINGLE_LANES, E = f32>> Read<A> for Block<'_> {
    #[inline(always)]
    fn lanes(&self, arith: A, k: usize) -> Lanes<A, SINGLE_LANES> {
        Lanes::block(arith, &self.view.c[k][self.i0..])
    }
}

/// Four voxels of one component: `i0..i0 + 4`, or gathered.
trait ReadHalf {
    fn half(&self, c: &[f32]) -> [f32; LANES];
}

/// Voxels `i0..i0 + 4` (a run of four links), one 128-bit load.
struct Run4(usize);

impl ReadHalf for Run4 {
    #[inline(always)]
    fn half(&self, c: &[f32]) -> [f32; LANES] {
        *c[self.0..].first_chunk().expect("a run of four voxels")
    }
}

/// Voxels `index[j]`, one by one.
struct Gather4([usize; LANES]);

impl ReadHalf for Gather4 {
    #[inline(always)]
    fn half(&self, c: &[f32]) -> [f32; LANES] {
        let i = &self.0;
        [c[i[0]], c[i[1]], c[i[2]], c[i[3]]]
    }
}

/// Eight voxels as two halves of four, each a run or gathered.
struct Halves<'a, Lo, Hi> {
    view: &'a SingleView<'a>,
    lo: Lo,
    hi: Hi,
}

impl<A: Widen, Lo: ReadHalf, Hi: ReadHalf> Read<A> for Halves<'_, Lo, Hi> {
    #[inline(always)]
    fn lanes(&self, arith: A, k: usize) -> Lanes<A, SINGLE_LANES> {
        let c = self.view.c[k];
        Lanes {
            v: arith.join(self.lo.half(c), self.hi.half(c)),
            arith,
        }
    }
}

/// The a and b ends of links `h..h + 4`, a run of four.
#[inline(always)]
fn run4(ends: &[(usize, usize, u8); SINGLE_LANES], h: usize) -> (Run4, Run4) {
    (Run4(ends[h].0), Run4(ends[h].1))
}

/// The a and b ends of links `h..h + 4`, gathered.
#[inline(always)]
fn gather4(ends: &[(usize, usize, u8); SINGLE_LANES], h: usize) -> (Gather4, Gather4) {
    let e = |j: usize| ends[h + j];
    let (e0, e1, e2, e3) = (e(0), e(1), e(2), e(3));
    (
        Gather4([e0.0, e1.0, e2.0, e3.0]),
        Gather4([e0.1, e1.1, e2.1, e3.1]),
    )
}

/// What the kernel reads of eight links whose halves `lo` and `hi` (a and b ends each) are runs
/// of four or gathered.
#[inline(always)]
fn half_ends<A: Widen, Lo: ReadHalf, Hi: ReadHalf, const DAMPED: bool>(
    arith: A,
    view: &SingleView,
    lo: (Lo, Lo),
    hi: (Hi, Hi),
) -> Ends<A, SINGLE_LANES> {
    let a = Halves {
        view,
        lo: lo.0,
        hi: hi.0,
    };
    let b = Halves {
        view,
        lo: lo.1,
        hi: hi.1,
    };
    ends::<A, DAMPED>(arith, a, b)
}

/// What the kernel reads of the links from the voxels `a` reads to those `b` reads.
#[inline(always)]
fn ends<A: Arith<SINGLE_LANES, E = f32>, const DAMPED: bool>(
    arith: A,
    a: impl Read<A>,
    b: impl Read<A>,
) -> Ends<A, SINGLE_LANES> {
    let zero = V3::splat(arith, 0.0);
    let (mut va, mut vb, mut wa, mut wb) = (zero, zero, zero, zero);
    if DAMPED {
        (va, vb) = (a.v3(arith, VELOCITY), b.v3(arith, VELOCITY));
        (wa, wb) = (a.v3(arith, SPIN), b.v3(arith, SPIN));
    }
    Ends {
        qa: a.quat(arith),
        qb: b.quat(arith),
        r: b.v3(arith, POSITION) - a.v3(arith, POSITION),
        va,
        vb,
        wa,
        wb,
    }
}

impl<A: Widen> Source<A, SINGLE_LANES> for SingleView<'_> {
    #[inline(always)]
    fn len(&self) -> usize {
        self.c[0].len()
    }

    #[inline(always)]
    fn cut(self) -> Self {
        let mut c = self.c;
        let n = c[0].len();
        for component in &mut c {
            *component = &component[..n];
        }
        Self { c }
    }

    #[inline(always)]
    fn gather<const DAMPED: bool>(
        &self,
        arith: A,
        ends_of: &[(usize, usize, u8); SINGLE_LANES],
    ) -> Ends<A, SINGLE_LANES> {
        // Not a run of eight, but often two runs of four, or one (the interior of a body whose
        // rows are not multiples of eight long): such a half is one 128-bit load.
        let h = LANES;
        match (run_of_four(ends_of, 0), run_of_four(ends_of, h)) {
            (false, false) => {
                half_ends::<A, _, _, DAMPED>(arith, self, gather4(ends_of, 0), gather4(ends_of, h))
            }
            (true, true) => {
                half_ends::<A, _, _, DAMPED>(arith, self, run4(ends_of, 0), run4(ends_of, h))
            }
            (true, false) => {
                half_ends::<A, _, _, DAMPED>(arith, self, run4(ends_of, 0), gather4(ends_of, h))
            }
            (false, true) => {
                half_ends::<A, _, _, DAMPED>(arith, self, gather4(ends_of, 0), run4(ends_of, h))
            }
        }
    }

    #[inline(always)]
    fn gather_run<const DAMPED: bool>(
        &self,
        arith: A,
        a0: usize,
        b0: usize,
    ) -> Ends<A, SINGLE_LANES> {
        let (a, b) = (Block { view: self, i0: a0 }, Block { view: self, i0: b0 });
        ends::<A, DAMPED>(arith, a, b)
    }
}

#[cfg(test)]
mod tests;
