//! Lane arithmetic for the link kernel and the integration: several links or voxels at once.
//!
//! The kernel is written once, on [`Lanes`], and compiled for two instruction sets through the
//! [`Arith`] token it carries: [`Portable`] (plain array loops, whatever the compiler makes of
//! them) and `pulp`'s AVX2 token (explicit vector instructions), each in double precision (four
//! `f64` lanes) and, wrapped in [`super::single_lanes::Single`], in single precision (eight `f32`
//! lanes). Explicit vectors make the vector code a property of the source: left to the optimizer,
//! a change as small as removing a bounds check turned the whole kernel back into scalar code
//! (docs/explanation/physics.md). Both use only IEEE addition, subtraction, multiplication and
//! division per lane, besides sign flips and selects, never a fused multiply-add, so they give the
//! same bits.

use pulp::Simd;

use super::math::{Quat, Vec3};

/// Voxels or links computed together in double precision, one per lane.
pub const LANES: usize = 4;

/// A lane's number type: `f64`, or `f32` for the single-precision kernel.
pub trait Element: Copy + Default + PartialOrd + 'static {
    /// `x` rounded to this type (to nearest, as `as` does).
    fn of(x: f64) -> Self;
    /// The value as an `f64` (exact).
    fn wide(self) -> f64;
}

impl Element for f64 {
    #[inline(always)]
    fn of(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn wide(self) -> f64 {
        self
    }
}

impl Element for f32 {
    #[inline(always)]
    fn of(x: f64) -> Self {
        x as f32
    }
    #[inline(always)]
    fn wide(self) -> f64 {
        f64::from(self)
    }
}

/// The arithmetic of one instruction set on a vector of `L` numbers of type `E`.
pub trait Arith<const L: usize>: Copy {
    type E: Element;
    type V: Copy;
    fn splat(self, x: Self::E) -> Self::V;
    fn vector(self, a: [Self::E; L]) -> Self::V;
    fn to_array(self, v: Self::V) -> [Self::E; L];
    fn add(self, a: Self::V, b: Self::V) -> Self::V;
    fn sub(self, a: Self::V, b: Self::V) -> Self::V;
    fn mul(self, a: Self::V, b: Self::V) -> Self::V;
    fn div(self, a: Self::V, b: Self::V) -> Self::V;
    /// The correctly rounded square root, as `f64::sqrt`.
    fn sqrt(self, a: Self::V) -> Self::V;
    /// −a, by its sign bit (as scalar negation: zeros and NaNs too).
    fn neg(self, a: Self::V) -> Self::V;
    /// Per lane, `a` where `key` equals `k`, else `b`.
    fn select_eq(self, key: Self::V, k: Self::E, a: Self::V, b: Self::V) -> Self::V;
    /// Per lane, `a` where `x` < 0, else `b` (NaN: `b`).
    fn select_negative(self, x: Self::V, a: Self::V, b: Self::V) -> Self::V;
    /// Per lane, `m.max(|x|)` for a running maximum `m` that is never NaN (a NaN `x` is skipped,
    /// as `f64::max` skips it).
    fn max_abs(self, m: Self::V, x: Self::V) -> Self::V;
    /// Whether every lane is below `k` (false where one is NaN).
    fn all_below(self, v: Self::V, k: Self::E) -> bool;
}

/// Four `f64` lanes, with the regroupings that read and write blocks of four voxels' `Vec3`s and
/// `Quat`s as whole vectors.
pub trait Regroup: Arith<LANES, E = f64> {
    /// Four 4-vectors, one per lane, as they lie in memory (w0 x0 y0 z0 w1 …: a block of four
    /// quaternions, one vector each), regrouped into one vector per component.
    fn columns4(self, image: [Self::V; 4]) -> [Self::V; 4];
    /// Four 3-vectors, one per lane, as they lie in memory (x0 y0 z0 x1 | y1 z1 x2 y2 |
    /// z2 x3 y3 z3), regrouped into one vector per component.
    fn columns3(self, image: [Self::V; 3]) -> [Self::V; 3];
    /// The inverse of [`Regroup::columns3`]: the memory image of one 3-vector per lane.
    fn image3(self, columns: [Self::V; 3]) -> [Self::V; 3];
    /// Each lane rounded to `f32` (to nearest).
    fn narrow(self, v: Self::V) -> [f32; LANES];
}

/// Any CPU: arrays, lane by lane.
#[derive(Clone, Copy)]
pub struct Portable;

/// `impl Arith<$lanes> for $token` on plain arrays of `$e`, lane by lane: the portable arithmetic of
/// either precision ([`Portable`] here, `Single<Portable>` in `super::single`).
macro_rules! portable_arith {
    ($token:ty, $e:ty, $lanes:expr) => {
        impl $crate::dynamics::lanes::Arith<{ $lanes }> for $token {
            type E = $e;
            type V = [$e; $lanes];
            #[inline(always)]
            fn splat(self, x: $e) -> Self::V {
                [x; $lanes]
            }
            #[inline(always)]
            fn vector(self, a: Self::V) -> Self::V {
                a
            }
            #[inline(always)]
            fn to_array(self, v: Self::V) -> Self::V {
                v
            }
            #[inline(always)]
            fn add(self, a: Self::V, b: Self::V) -> Self::V {
                std::array::from_fn(|j| a[j] + b[j])
            }
            #[inline(always)]
            fn sub(self, a: Self::V, b: Self::V) -> Self::V {
                std::array::from_fn(|j| a[j] - b[j])
            }
            #[inline(always)]
            fn mul(self, a: Self::V, b: Self::V) -> Self::V {
                std::array::from_fn(|j| a[j] * b[j])
            }
            #[inline(always)]
            fn div(self, a: Self::V, b: Self::V) -> Self::V {
                std::array::from_fn(|j| a[j] / b[j])
            }
            #[inline(always)]
            fn sqrt(self, a: Self::V) -> Self::V {
                a.map(<$e>::sqrt)
            }
            #[inline(always)]
            fn neg(self, a: Self::V) -> Self::V {
                a.map(|a| -a)
            }
            #[inline(always)]
            fn select_eq(self, key: Self::V, k: $e, a: Self::V, b: Self::V) -> Self::V {
                std::array::from_fn(|j| if key[j] == k { a[j] } else { b[j] })
            }
            #[inline(always)]
            fn select_negative(self, x: Self::V, a: Self::V, b: Self::V) -> Self::V {
                std::array::from_fn(|j| if x[j] < 0.0 { a[j] } else { b[j] })
            }
            #[inline(always)]
            fn max_abs(self, m: Self::V, x: Self::V) -> Self::V {
                std::array::from_fn(|j| m[j].max(x[j].abs()))
            }
            #[inline(always)]
            fn all_below(self, v: Self::V, k: $e) -> bool {
                v.iter().all(|&x| x < k)
            }
        }
    };
}
pub(super) use portable_arith;

portable_arith!(Portable, f64, LANES);

impl Regroup for Portable {
    #[inline(always)]
    fn columns4(self, image: [Self::V; 4]) -> [Self::V; 4] {
        std::array::from_fn(|c| std::array::from_fn(|j| image[j][c]))
    }
    #[inline(always)]
    fn columns3(self, image: [Self::V; 3]) -> [Self::V; 3] {
        let flat: [f64; 12] = bytemuck::cast(image);
        std::array::from_fn(|c| std::array::from_fn(|j| flat[3 * j + c]))
    }
    #[inline(always)]
    fn image3(self, columns: [Self::V; 3]) -> [Self::V; 3] {
        let flat: [f64; 12] = std::array::from_fn(|k| columns[k % 3][k / 3]);
        bytemuck::cast(flat)
    }
    #[inline(always)]
    fn narrow(self, v: Self::V) -> [f32; LANES] {
        v.map(|x| x as f32)
    }
}

/// x86-64 with AVX2 (chosen at run time): one 256-bit register per vector.
impl Arith<LANES> for pulp::x86::V3 {
    type E = f64;
    type V = pulp::f64x4;
    #[inline(always)]
    fn splat(self, x: f64) -> Self::V {
        self.splat_f64s(x)
    }
    #[inline(always)]
    fn vector(self, a: [f64; LANES]) -> Self::V {
        pulp::f64x4(a[0], a[1], a[2], a[3])
    }
    #[inline(always)]
    fn to_array(self, v: Self::V) -> [f64; LANES] {
        [v.0, v.1, v.2, v.3]
    }
    #[inline(always)]
    fn add(self, a: Self::V, b: Self::V) -> Self::V {
        self.add_f64s(a, b)
    }
    #[inline(always)]
    fn sub(self, a: Self::V, b: Self::V) -> Self::V {
        self.sub_f64s(a, b)
    }
    #[inline(always)]
    fn mul(self, a: Self::V, b: Self::V) -> Self::V {
        self.mul_f64s(a, b)
    }
    #[inline(always)]
    fn div(self, a: Self::V, b: Self::V) -> Self::V {
        self.div_f64s(a, b)
    }
    #[inline(always)]
    fn sqrt(self, a: Self::V) -> Self::V {
        self.sqrt_f64s(a)
    }
    #[inline(always)]
    fn neg(self, a: Self::V) -> Self::V {
        self.xor_f64s(a, self.splat_f64s(-0.0))
    }
    #[inline(always)]
    fn select_eq(self, key: Self::V, k: f64, a: Self::V, b: Self::V) -> Self::V {
        self.select_f64s(self.equal_f64s(key, self.splat_f64s(k)), a, b)
    }
    #[inline(always)]
    fn select_negative(self, x: Self::V, a: Self::V, b: Self::V) -> Self::V {
        self.select_f64s(self.less_than_f64s(x, self.splat_f64s(0.0)), a, b)
    }
    #[inline(always)]
    fn max_abs(self, m: Self::V, x: Self::V) -> Self::V {
        let x = self.abs_f64s(x);
        self.select_f64s(self.less_than_f64s(m, x), x, m)
    }
    #[inline(always)]
    fn all_below(self, v: Self::V, k: f64) -> bool {
        let below = self.less_than_f64s(v, self.splat_f64s(k));
        self.avx._mm256_movemask_pd(pulp::cast(below)) == 0b1111
    }
}

impl Regroup for pulp::x86::V3 {
    #[inline(always)]
    fn columns4(self, image: [Self::V; 4]) -> [Self::V; 4] {
        use std::arch::x86_64::__m256d;
        let avx = self.avx;
        let r: [__m256d; 4] = image.map(pulp::cast);
        let (t0, t1) = (
            avx._mm256_unpacklo_pd(r[0], r[1]),
            avx._mm256_unpackhi_pd(r[0], r[1]),
        );
        let (t2, t3) = (
            avx._mm256_unpacklo_pd(r[2], r[3]),
            avx._mm256_unpackhi_pd(r[2], r[3]),
        );
        [
            avx._mm256_permute2f128_pd::<0x20>(t0, t2),
            avx._mm256_permute2f128_pd::<0x20>(t1, t3),
            avx._mm256_permute2f128_pd::<0x31>(t0, t2),
            avx._mm256_permute2f128_pd::<0x31>(t1, t3),
        ]
        .map(pulp::cast)
    }
    #[inline(always)]
    fn columns3(self, image: [Self::V; 3]) -> [Self::V; 3] {
        use std::arch::x86_64::__m256d;
        let avx = self.avx;
        // The halves are regrouped, then interleaved into x, y and z.
        let v: [__m256d; 3] = image.map(pulp::cast);
        let ends = avx._mm256_permute2f128_pd::<0x30>(v[0], v[2]); // x0 y0 | y3 z3
        let middle = avx._mm256_permute2f128_pd::<0x21>(v[0], v[2]); // z0 x1 | z2 x3
        let xy = avx._mm256_blend_pd::<0b1100>(ends, v[1]); // x0 y0 | x2 y2
        let yz = avx._mm256_blend_pd::<0b1100>(v[1], ends); // y1 z1 | y3 z3
        [
            avx._mm256_shuffle_pd::<0b1010>(xy, middle),
            avx._mm256_shuffle_pd::<0b0101>(xy, yz),
            avx._mm256_shuffle_pd::<0b1010>(middle, yz),
        ]
        .map(pulp::cast)
    }
    #[inline(always)]
    fn image3(self, columns: [Self::V; 3]) -> [Self::V; 3] {
        use std::arch::x86_64::__m256d;
        let avx = self.avx;
        let [x, y, z]: [__m256d; 3] = columns.map(pulp::cast);
        let xy = avx._mm256_shuffle_pd::<0b0000>(x, y); // x0 y0 | x2 y2
        let yz = avx._mm256_shuffle_pd::<0b1111>(y, z); // y1 z1 | y3 z3
        let middle = avx._mm256_shuffle_pd::<0b1010>(z, x); // z0 x1 | z2 x3
        [
            avx._mm256_permute2f128_pd::<0x20>(xy, middle),
            avx._mm256_blend_pd::<0b1100>(yz, xy),
            avx._mm256_permute2f128_pd::<0x31>(middle, yz),
        ]
        .map(pulp::cast)
    }
    #[inline(always)]
    fn narrow(self, v: Self::V) -> [f32; LANES] {
        pulp::cast(self.avx._mm256_cvtpd_ps(pulp::cast(v)))
    }
}

/// `[f(0), …, f(L − 1)]`, always inlined: `std::array::from_fn` is left to the optimizer's
/// judgement, and where it was not inlined (eight lanes, as the mixed-precision kernel uses) the
/// kernel around it lost its vector code.
#[inline(always)]
pub fn lane_array<T: Copy + Default, const L: usize>(mut f: impl FnMut(usize) -> T) -> [T; L] {
    let mut a = [T::default(); L];
    for (j, x) in a.iter_mut().enumerate() {
        *x = f(j);
    }
    a
}

/// One number per lane, with the token of the instruction set that computes it.
#[derive(Clone, Copy)]
pub struct Lanes<A: Arith<L>, const L: usize> {
    pub v: A::V,
    pub arith: A,
}

/// Four `f64` lanes.
pub type Lanes4<A> = Lanes<A, LANES>;

impl<A: Arith<L>, const L: usize> Lanes<A, L> {
    /// `x` (rounded to the lanes' type) in every lane.
    #[inline(always)]
    pub fn splat(arith: A, x: f64) -> Self {
        Self {
            v: arith.splat(A::E::of(x)),
            arith,
        }
    }

    #[inline(always)]
    pub fn from_fn(arith: A, f: impl FnMut(usize) -> A::E) -> Self {
        Self {
            v: arith.vector(lane_array(f)),
            arith,
        }
    }

    #[inline(always)]
    pub fn to_array(self) -> [A::E; L] {
        self.arith.to_array(self.v)
    }

    #[inline(always)]
    pub fn sqrt(self) -> Self {
        Self {
            v: self.arith.sqrt(self.v),
            arith: self.arith,
        }
    }

    /// `src[k0..k0 + L]`, the last entry repeated past the end of `src`.
    #[inline(always)]
    pub fn load(arith: A, src: &[A::E], k0: usize) -> Self {
        match src.get(k0..k0 + L) {
            Some(s) => Self::block(arith, s),
            None => Self::from_fn(arith, |j| src[(k0 + j).min(src.len() - 1)]),
        }
    }

    /// The first `L` entries of `block`, as one vector load (filled lane by lane, the eight-lane
    /// kernel stored each entry to the stack and loaded them back).
    #[inline(always)]
    pub fn block(arith: A, block: &[A::E]) -> Self {
        let a: &[A::E; L] = block.first_chunk().expect("a block of L entries");
        Self {
            v: arith.vector(*a),
            arith,
        }
    }
}

macro_rules! lane_op {
    ($trait:ident, $method:ident) => {
        impl<A: Arith<L>, const L: usize> std::ops::$trait for Lanes<A, L> {
            type Output = Self;
            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                Self {
                    v: self.arith.$method(self.v, o.v),
                    arith: self.arith,
                }
            }
        }
    };
}
lane_op!(Add, add);
lane_op!(Sub, sub);
lane_op!(Mul, mul);
lane_op!(Div, div);

impl<A: Arith<L>, const L: usize> std::ops::Mul<f64> for Lanes<A, L> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: f64) -> Self {
        self * Self::splat(self.arith, o)
    }
}

impl<A: Arith<L>, const L: usize> std::ops::Neg for Lanes<A, L> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self {
            v: self.arith.neg(self.v),
            arith: self.arith,
        }
    }
}

/// Four consecutive voxels' 3-vectors as the memory image [`Regroup::columns3`] regroups.
#[inline(always)]
pub fn load_image3<A: Regroup>(arith: A, block: &[Vec3]) -> [A::V; 3] {
    let block: [Vec3; LANES] = std::array::from_fn(|j| block[j]);
    bytemuck::cast::<_, [[f64; LANES]; 3]>(block).map(|v| arith.vector(v))
}

/// Writes a memory image back over four consecutive voxels' 3-vectors.
#[inline(always)]
pub fn store_image3<A: Regroup>(arith: A, block: &mut [Vec3], image: [A::V; 3]) {
    let values: [Vec3; LANES] = bytemuck::cast(image.map(|v| arith.to_array(v)));
    block[..LANES].copy_from_slice(&values);
}

/// Adds (or, `SUBTRACT`, takes) a memory image of four 3-vectors to four consecutive voxels'.
#[inline(always)]
pub fn add_image3<const SUBTRACT: bool, A: Regroup>(
    arith: A,
    block: &mut [Vec3],
    delta: [A::V; 3],
) {
    let now = load_image3(arith, block);
    let new = std::array::from_fn(|c| {
        if SUBTRACT {
            arith.sub(now[c], delta[c])
        } else {
            arith.add(now[c], delta[c])
        }
    });
    store_image3(arith, block, new);
}

/// Four consecutive voxels' 3-vectors, one vector per component.
#[inline(always)]
pub fn load_columns3<A: Regroup>(arith: A, block: &[Vec3]) -> [Lanes4<A>; 3] {
    arith
        .columns3(load_image3(arith, block))
        .map(|v| Lanes { v, arith })
}

/// Four consecutive voxels' quaternions, one vector per component (w, x, y, z).
#[inline(always)]
pub fn load_columns4<A: Regroup>(arith: A, block: &[Quat]) -> [Lanes4<A>; 4] {
    let block: [Quat; LANES] = std::array::from_fn(|j| block[j]);
    let image = bytemuck::cast::<_, [[f64; LANES]; 4]>(block).map(|v| arith.vector(v));
    arith.columns4(image).map(|v| Lanes { v, arith })
}

/// Writes one vector per component back over four consecutive voxels' quaternions.
#[inline(always)]
pub fn store_columns4<A: Regroup>(arith: A, block: &mut [Quat], columns: [Lanes4<A>; 4]) {
    // The transposition is its own inverse.
    let image = arith.columns4(columns.map(|c| c.v));
    let values: [Quat; LANES] = bytemuck::cast(image.map(|v| arith.to_array(v)));
    block[..LANES].copy_from_slice(&values);
}

#[cfg(test)]
mod tests;
