//! Lane arithmetic for the link kernel: four links at once, one `f64` per lane.
//!
//! The kernel is written once, on [`Lanes`], and compiled for two instruction sets through the
//! [`Arith`] token it carries: [`Portable`] (plain `[f64; 4]` loops, whatever the compiler makes of
//! them) and `pulp`'s AVX2 token (explicit 4-wide vector instructions). Explicit vectors make the
//! vector code a property of the source: left to the optimizer, a change as small as removing
//! a bounds check turned the whole kernel back into scalar code (docs/dynamics.md, "Speed").
//! Both use only IEEE addition, subtraction, multiplication and division per lane, besides sign
//! flips and selects, never a fused multiply-add, so they give the same bits.

use pulp::Simd;

/// Links computed together, one per lane.
pub const LANES: usize = 4;

/// The arithmetic of one instruction set on a vector of [`LANES`] `f64`s.
pub trait Arith: Copy {
    type V: Copy;
    fn splat(self, x: f64) -> Self::V;
    fn vector(self, a: [f64; LANES]) -> Self::V;
    fn to_array(self, v: Self::V) -> [f64; LANES];
    fn add(self, a: Self::V, b: Self::V) -> Self::V;
    fn sub(self, a: Self::V, b: Self::V) -> Self::V;
    fn mul(self, a: Self::V, b: Self::V) -> Self::V;
    fn div(self, a: Self::V, b: Self::V) -> Self::V;
    /// −a, by its sign bit (as scalar negation: zeros and NaNs too).
    fn neg(self, a: Self::V) -> Self::V;
    /// Per lane, `a` where `key` equals `k`, else `b`.
    fn select_eq(self, key: Self::V, k: f64, a: Self::V, b: Self::V) -> Self::V;
    /// Per lane, `a` where `x` < 0, else `b` (NaN: `b`).
    fn select_negative(self, x: Self::V, a: Self::V, b: Self::V) -> Self::V;
    /// Per lane, `m.max(|x|)` for a running maximum `m` that is never NaN (a NaN `x` is skipped,
    /// as `f64::max` skips it).
    fn max_abs(self, m: Self::V, x: Self::V) -> Self::V;
}

/// Any CPU: arrays, lane by lane.
#[derive(Clone, Copy)]
pub struct Portable;

impl Portable {
    #[inline(always)]
    fn zip(a: [f64; LANES], b: [f64; LANES], f: impl Fn(f64, f64) -> f64) -> [f64; LANES] {
        std::array::from_fn(|j| f(a[j], b[j]))
    }
}

impl Arith for Portable {
    type V = [f64; LANES];
    #[inline(always)]
    fn splat(self, x: f64) -> Self::V {
        [x; LANES]
    }
    #[inline(always)]
    fn vector(self, a: [f64; LANES]) -> Self::V {
        a
    }
    #[inline(always)]
    fn to_array(self, v: Self::V) -> [f64; LANES] {
        v
    }
    #[inline(always)]
    fn add(self, a: Self::V, b: Self::V) -> Self::V {
        Self::zip(a, b, |a, b| a + b)
    }
    #[inline(always)]
    fn sub(self, a: Self::V, b: Self::V) -> Self::V {
        Self::zip(a, b, |a, b| a - b)
    }
    #[inline(always)]
    fn mul(self, a: Self::V, b: Self::V) -> Self::V {
        Self::zip(a, b, |a, b| a * b)
    }
    #[inline(always)]
    fn div(self, a: Self::V, b: Self::V) -> Self::V {
        Self::zip(a, b, |a, b| a / b)
    }
    #[inline(always)]
    fn neg(self, a: Self::V) -> Self::V {
        a.map(|a| -a)
    }
    #[inline(always)]
    fn select_eq(self, key: Self::V, k: f64, a: Self::V, b: Self::V) -> Self::V {
        std::array::from_fn(|j| if key[j] == k { a[j] } else { b[j] })
    }
    #[inline(always)]
    fn select_negative(self, x: Self::V, a: Self::V, b: Self::V) -> Self::V {
        std::array::from_fn(|j| if x[j] < 0.0 { a[j] } else { b[j] })
    }
    #[inline(always)]
    fn max_abs(self, m: Self::V, x: Self::V) -> Self::V {
        Self::zip(m, x, |m, x| m.max(x.abs()))
    }
}

/// x86-64 with AVX2 (chosen at run time): one 256-bit register per vector.
impl Arith for pulp::x86::V3 {
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
}

/// One `f64` per lane, with the token of the instruction set that computes it.
#[derive(Clone, Copy)]
pub struct Lanes<A: Arith> {
    pub v: A::V,
    pub arith: A,
}

impl<A: Arith> Lanes<A> {
    #[inline(always)]
    pub fn splat(arith: A, x: f64) -> Self {
        Self {
            v: arith.splat(x),
            arith,
        }
    }

    #[inline(always)]
    pub fn from_fn(arith: A, f: impl FnMut(usize) -> f64) -> Self {
        Self {
            v: arith.vector(std::array::from_fn(f)),
            arith,
        }
    }

    #[inline(always)]
    pub fn to_array(self) -> [f64; LANES] {
        self.arith.to_array(self.v)
    }

    /// `src[k0..k0 + LANES]`, the last entry repeated past the end of `src`.
    #[inline(always)]
    pub fn load(arith: A, src: &[f64], k0: usize) -> Self {
        match src.get(k0..k0 + LANES) {
            Some(s) => Self::from_fn(arith, |j| s[j]),
            None => Self::from_fn(arith, |j| src[(k0 + j).min(src.len() - 1)]),
        }
    }
}

macro_rules! lane_op {
    ($trait:ident, $method:ident) => {
        impl<A: Arith> std::ops::$trait for Lanes<A> {
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

impl<A: Arith> std::ops::Mul<f64> for Lanes<A> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: f64) -> Self {
        self * Self::splat(self.arith, o)
    }
}

impl<A: Arith> std::ops::Neg for Lanes<A> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self {
            v: self.arith.neg(self.v),
            arith: self.arith,
        }
    }
}
