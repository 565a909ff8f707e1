//! The mixed kernel's arithmetic: eight `f32` lanes on the instruction set of a double-precision
//! token ([`Single`]), the kernel over them, and the widening of each group's results to two
//! groups of four `f64` lanes for the voxels ([`Widen`]); see [`super::single`] for why.

use pulp::Simd;

use super::lanes::{Arith, LANES, Lanes, Portable, Regroup, portable_arith};
use super::link_ends::{Group, Kernel, LinkOut, Loads};
use super::link_frame::V3;

/// Links computed together in single precision, one per lane.
pub const SINGLE_LANES: usize = 8;

/// The single-precision arithmetic of a double-precision token: eight `f32` lanes.
#[derive(Clone, Copy, Debug)]
pub struct Single<T>(pub T);

/// Eight `f32` lanes whose results reach the voxels as two groups of four `f64` lanes.
pub(super) trait Widen: Arith<SINGLE_LANES, E = f32> {
    /// The double-precision token of the same instruction set.
    type Wide: Regroup;
    fn wide(self) -> Self::Wide;
    /// Lanes 0–3 and 4–7, each converted to `f64` (exactly).
    fn halves(self, v: Self::V) -> [<Self::Wide as Arith<LANES>>::V; 2];
    /// Lanes 0–3 from `lo`, 4–7 from `hi`.
    fn join(self, lo: [f32; LANES], hi: [f32; LANES]) -> Self::V;
}

portable_arith!(Single<Portable>, f32, SINGLE_LANES);

impl Widen for Single<Portable> {
    type Wide = Portable;
    #[inline(always)]
    fn wide(self) -> Portable {
        self.0
    }
    #[inline(always)]
    fn halves(self, v: Self::V) -> [[f64; LANES]; 2] {
        [
            std::array::from_fn(|j| f64::from(v[j])),
            std::array::from_fn(|j| f64::from(v[LANES + j])),
        ]
    }
    #[inline(always)]
    fn join(self, lo: [f32; LANES], hi: [f32; LANES]) -> Self::V {
        [lo[0], lo[1], lo[2], lo[3], hi[0], hi[1], hi[2], hi[3]]
    }
}

/// x86-64 with AVX2 (chosen at run time): eight `f32`s in one 256-bit register.
impl Arith<SINGLE_LANES> for Single<pulp::x86::V3> {
    type E = f32;
    type V = pulp::f32x8;
    #[inline(always)]
    fn splat(self, x: f32) -> Self::V {
        self.0.splat_f32s(x)
    }
    #[inline(always)]
    fn vector(self, a: [f32; SINGLE_LANES]) -> Self::V {
        pulp::cast(a)
    }
    #[inline(always)]
    fn to_array(self, v: Self::V) -> [f32; SINGLE_LANES] {
        pulp::cast(v)
    }
    #[inline(always)]
    fn add(self, a: Self::V, b: Self::V) -> Self::V {
        self.0.add_f32s(a, b)
    }
    #[inline(always)]
    fn sub(self, a: Self::V, b: Self::V) -> Self::V {
        self.0.sub_f32s(a, b)
    }
    #[inline(always)]
    fn mul(self, a: Self::V, b: Self::V) -> Self::V {
        self.0.mul_f32s(a, b)
    }
    #[inline(always)]
    fn div(self, a: Self::V, b: Self::V) -> Self::V {
        self.0.div_f32s(a, b)
    }
    #[inline(always)]
    fn sqrt(self, a: Self::V) -> Self::V {
        self.0.sqrt_f32s(a)
    }
    #[inline(always)]
    fn neg(self, a: Self::V) -> Self::V {
        self.0.xor_f32s(a, self.0.splat_f32s(-0.0))
    }
    #[inline(always)]
    fn select_eq(self, key: Self::V, k: f32, a: Self::V, b: Self::V) -> Self::V {
        let s = self.0;
        s.select_f32s(s.equal_f32s(key, s.splat_f32s(k)), a, b)
    }
    #[inline(always)]
    fn select_negative(self, x: Self::V, a: Self::V, b: Self::V) -> Self::V {
        let s = self.0;
        s.select_f32s(s.less_than_f32s(x, s.splat_f32s(0.0)), a, b)
    }
    #[inline(always)]
    fn max_abs(self, m: Self::V, x: Self::V) -> Self::V {
        let s = self.0;
        let x = s.abs_f32s(x);
        s.select_f32s(s.less_than_f32s(m, x), x, m)
    }
    #[inline(always)]
    fn all_below(self, v: Self::V, k: f32) -> bool {
        let s = self.0;
        let below = s.less_than_f32s(v, s.splat_f32s(k));
        s.avx._mm256_movemask_ps(pulp::cast(below)) == 0xff
    }
}

impl Widen for Single<pulp::x86::V3> {
    type Wide = pulp::x86::V3;
    #[inline(always)]
    fn wide(self) -> pulp::x86::V3 {
        self.0
    }
    #[inline(always)]
    fn halves(self, v: Self::V) -> [pulp::f64x4; 2] {
        use std::arch::x86_64::__m256;
        let avx = self.0.avx;
        let v: __m256 = pulp::cast(v);
        [
            pulp::cast(avx._mm256_cvtps_pd(avx._mm256_castps256_ps128(v))),
            pulp::cast(avx._mm256_cvtps_pd(avx._mm256_extractf128_ps::<1>(v))),
        ]
    }
    #[inline(always)]
    fn join(self, lo: [f32; LANES], hi: [f32; LANES]) -> Self::V {
        pulp::cast(self.0.avx._mm256_set_m128(pulp::cast(hi), pulp::cast(lo)))
    }
}

impl<T: Copy> Kernel<SINGLE_LANES> for Single<T>
where
    Single<T>: Widen,
{
    #[inline(always)]
    fn put<O: LinkOut>(
        self,
        out: &mut O,
        group: Group<SINGLE_LANES>,
        loads: Loads<Self, SINGLE_LANES>,
    ) {
        // Both halves of each component, converted once (in functions, not closures: a closure
        // is compiled without the vector instructions of the function around it).
        let (f_b, m_a, m_b) = (
            halves(self, loads.f_b),
            halves(self, loads.m_a),
            halves(self, loads.m_b),
        );
        for h in 0..SINGLE_LANES / LANES {
            let first = LANES * h;
            if group.count <= first {
                break;
            }
            let mut ends = [(0, 0, 0); LANES];
            ends.copy_from_slice(&group.ends[first..first + LANES]);
            // Four consecutive voxels linked to four: added as blocks, as the double kernel does.
            let run = group.count >= first + LANES && run_of_four(group.ends, first);
            let half = Group {
                k0: group.k0 + first,
                count: (group.count - first).min(LANES),
                ends: &ends,
                run,
            };
            let loads = Loads {
                f_b: f_b[h],
                m_a: m_a[h],
                m_b: m_b[h],
            };
            out.put(half, loads);
        }
    }
}

/// Lanes 0–3 and 4–7 of a 3-vector, each converted to `f64` (exactly).
#[inline(always)]
pub(super) fn halves<A: Widen>(arith: A, v: V3<A, SINGLE_LANES>) -> [V3<A::Wide, LANES>; 2] {
    let wide = arith.wide();
    let (x, y, z) = (
        arith.halves(v.x.v),
        arith.halves(v.y.v),
        arith.halves(v.z.v),
    );
    [
        V3 {
            x: Lanes {
                v: x[0],
                arith: wide,
            },
            y: Lanes {
                v: y[0],
                arith: wide,
            },
            z: Lanes {
                v: z[0],
                arith: wide,
            },
        },
        V3 {
            x: Lanes {
                v: x[1],
                arith: wide,
            },
            y: Lanes {
                v: y[1],
                arith: wide,
            },
            z: Lanes {
                v: z[1],
                arith: wide,
            },
        },
    ]
}

/// Whether links `h..h + 4` of a group join four consecutive voxels to four consecutive voxels.
#[inline(always)]
pub(super) fn run_of_four(ends: &[(usize, usize, u8); SINGLE_LANES], h: usize) -> bool {
    let (a0, b0) = (ends[h].0, ends[h].1);
    let mut run = true;
    for j in 1..LANES {
        run &= ends[h + j].0 == a0 + j && ends[h + j].1 == b0 + j;
    }
    run
}
