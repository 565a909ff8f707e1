//! Several threads for one simulation, with the bits of one thread.
//!
//! A step run inside a `rayon` thread pool (`ThreadPool::install`) shares its two costly passes
//! among the pool's threads: the links and the integration (together ~97 % of a step; the other
//! passes stay serial). The single-thread link pass adds each link's forces to its two voxels as
//! it goes, which threads cannot share; here the links are cut into parts whose forces and
//! moments go to per-link slots (`link::link_loads`), and then the voxels are cut into parts that
//! each add their links' slots **in link order**, the order in which the single-thread pass adds
//! them. Every sum therefore takes the same operands in the same order, and the integration
//! updates each voxel on its own, so the state is the same bits as the single-thread step's for
//! any number of threads (test `threads_give_the_bits_of_one_thread`). What the parts return for
//! the divergence checks combines exactly in any order (maxima, and sums of zeros), so the cuts
//! may follow the number of threads.

use super::integrate::{IntegrationSummary, VoxelState, integrate_part};
use super::link::{LinkLoads, LinkStep, link_loads};
use super::math::Vec3;
use super::single::SingleCopy;
use super::state::{Links, Voxels};

/// Links in the smallest part a thread takes (a multiple of the kernel's four lanes).
const LINK_GRAIN: usize = 256;
/// Voxels in the smallest part a thread takes.
const VOXEL_GRAIN: usize = 128;

/// The part size for `n` items on the current pool: two parts per thread, so that a thread slowed
/// by other work on its core can hand part of its share to the others (1, 2, 4 and 8 parts per
/// thread measured alike within the build machine's noise), but no part smaller than
/// `least`; a multiple of four.
fn grain(n: usize, least: usize) -> usize {
    n.div_ceil(2 * rayon::current_num_threads())
        .next_multiple_of(4)
        .max(least)
}

/// The threads one evaluation runs on: the caller's alone, or a pool whose threads share each
/// simulation step run inside it ([`EvaluationThreads::run`]), with the same bits either way.
#[derive(Debug, Default)]
pub struct EvaluationThreads(Option<rayon::ThreadPool>);

impl EvaluationThreads {
    /// `threads` threads, named by `name` (thread j of the pool); 1 is the caller's thread alone.
    pub fn new(
        threads: usize,
        name: impl Fn(usize) -> String + 'static,
    ) -> Result<Self, rayon::ThreadPoolBuildError> {
        if threads <= 1 {
            return Ok(Self(None));
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(name)
            .build()?;
        Ok(Self(Some(pool)))
    }

    /// `f` (e.g. a task's evaluation) on these threads.
    pub fn run<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        match &self.0 {
            Some(pool) => pool.install(f),
            None => f(),
        }
    }
}

/// What a threaded step needs besides the simulation's state: which links each voxel adds, and
/// the per-link slots the link parts write.
#[derive(Clone, Debug)]
pub struct Threaded {
    /// Voxel i adds `ends[start[i]..start[i + 1]]`, in link order: 2k for the a end of link k,
    /// 2k + 1 for its b end.
    start: Vec<u32>,
    ends: Vec<u32>,
    force_b: Vec<Vec3>,
    moment_a: Vec<Vec3>,
    moment_b: Vec<Vec3>,
}

impl Threaded {
    pub fn new(links: &Links, voxel_count: usize) -> Self {
        let mut start = vec![0u32; voxel_count + 1];
        for k in 0..links.len() {
            start[links.a[k] as usize + 1] += 1;
            start[links.b[k] as usize + 1] += 1;
        }
        for i in 0..voxel_count {
            start[i + 1] += start[i];
        }
        let mut filled = start.clone();
        let mut ends = vec![0u32; 2 * links.len()];
        // Links in order, so that each voxel's list is in link order.
        for k in 0..links.len() {
            for (voxel, end) in [(links.a[k], 0), (links.b[k], 1)] {
                let slot = &mut filled[voxel as usize];
                ends[*slot as usize] = 2 * k as u32 + end;
                *slot += 1;
            }
        }
        let slots = vec![Vec3::ZERO; links.len()];
        Self {
            start,
            ends,
            force_b: slots.clone(),
            moment_a: slots.clone(),
            moment_b: slots,
        }
    }

    /// The link pass (`link::link_pass`, or with `single`, a copy of this step's state,
    /// `link::link_pass_mixed`) on the current pool's threads; returns the largest axial strain.
    pub fn link_pass<const DAMPED: bool, const ACTUATED: bool>(
        &mut self,
        links: &Links,
        voxels: &mut Voxels,
        single: Option<&SingleCopy>,
        step: LinkStep,
    ) -> f64 {
        let loads = LinkLoads {
            force_b: &mut self.force_b,
            moment_a: &mut self.moment_a,
            moment_b: &mut self.moment_b,
        };
        let state = &*voxels;
        let strain = in_parts(
            loads,
            0,
            grain(links.len(), LINK_GRAIN),
            &|part: LinkLoads, first| {
                let range = first..first + part.force_b.len();
                link_loads::<DAMPED, ACTUATED>(links, state, single, range, step, part)
            },
            &f64::max,
        );
        let n = voxels.len();
        let accumulators = Accumulators {
            force: &mut voxels.force[..n],
            torque: &mut voxels.torque[..n],
        };
        in_parts(
            accumulators,
            0,
            grain(n, VOXEL_GRAIN),
            &|part, first| self.add_loads(part, first),
            &|(), ()| (),
        );
        strain
    }

    /// The integration (`integrate::integrate_pass`) on the current pool's threads.
    pub fn integrate(voxels: &mut Voxels, dt: f64) -> IntegrationSummary {
        let n = voxels.len();
        in_parts(
            VoxelState::new(voxels),
            0,
            grain(n, VOXEL_GRAIN),
            &|part, _| integrate_part(part, dt),
            &IntegrationSummary::and,
        )
    }

    /// Adds to voxels `first..` (the part's accumulators) their links' slots in link order.
    fn add_loads(&self, part: Accumulators, first: usize) {
        for (i, (force, torque)) in part
            .force
            .iter_mut()
            .zip(part.torque.iter_mut())
            .enumerate()
        {
            let v = first + i;
            let (mut f, mut t) = (*force, *torque);
            for &end in &self.ends[self.start[v] as usize..self.start[v + 1] as usize] {
                let k = (end / 2) as usize;
                if end % 2 == 1 {
                    f += self.force_b[k];
                    t += self.moment_b[k];
                } else {
                    f -= self.force_b[k];
                    t += self.moment_a[k];
                }
            }
            *force = f;
            *torque = t;
        }
    }
}

/// The force and torque accumulators of a run of voxels.
struct Accumulators<'a> {
    force: &'a mut [Vec3],
    torque: &'a mut [Vec3],
}

/// Work that can be cut in two at an index.
trait Part: Sized + Send {
    fn len(&self) -> usize;
    fn split_at(self, mid: usize) -> (Self, Self);
}

impl Part for LinkLoads<'_> {
    fn len(&self) -> usize {
        self.force_b.len()
    }
    fn split_at(self, mid: usize) -> (Self, Self) {
        let (f1, f2) = self.force_b.split_at_mut(mid);
        let (a1, a2) = self.moment_a.split_at_mut(mid);
        let (b1, b2) = self.moment_b.split_at_mut(mid);
        (
            Self {
                force_b: f1,
                moment_a: a1,
                moment_b: b1,
            },
            Self {
                force_b: f2,
                moment_a: a2,
                moment_b: b2,
            },
        )
    }
}

impl Part for Accumulators<'_> {
    fn len(&self) -> usize {
        self.force.len()
    }
    fn split_at(self, mid: usize) -> (Self, Self) {
        let (f1, f2) = self.force.split_at_mut(mid);
        let (t1, t2) = self.torque.split_at_mut(mid);
        (
            Self {
                force: f1,
                torque: t1,
            },
            Self {
                force: f2,
                torque: t2,
            },
        )
    }
}

impl Part for VoxelState<'_> {
    fn len(&self) -> usize {
        VoxelState::len(self)
    }
    fn split_at(self, mid: usize) -> (Self, Self) {
        VoxelState::split_at(self, mid)
    }
}

/// `work` on parts of at most `grain` items (`first` is a part's first index in the whole), the
/// halves of each cut offered to other threads, and the results combined by `combine` in index
/// order. The cuts fall on multiples of `grain`.
fn in_parts<P: Part, R: Send>(
    part: P,
    first: usize,
    grain: usize,
    work: &(impl Fn(P, usize) -> R + Sync),
    combine: &(impl Fn(R, R) -> R + Sync),
) -> R {
    let n = part.len();
    if n <= grain {
        return work(part, first);
    }
    let mid = (n / grain).div_ceil(2) * grain;
    let (left, right) = part.split_at(mid);
    let (l, r) = rayon::join(
        || in_parts(left, first, grain, work, combine),
        || in_parts(right, first + mid, grain, work, combine),
    );
    combine(l, r)
}

#[cfg(test)]
mod tests;
