//! The link kernel's algebra, lane by lane: 3-vectors, the rotation matrix of the link frame,
//! and the per-lane choice between a link's axial and transverse constants (its axis is data,
//! not code, so links of all three directions share one vector).

use super::lanes::{Arith, Element, LANES, Lanes, Regroup, add_image3, load_columns3};
use super::math::{Quat, Vec3};

/// A 3-vector per lane.
#[derive(Clone, Copy)]
pub(super) struct V3<A: Arith<L>, const L: usize> {
    pub(super) x: Lanes<A, L>,
    pub(super) y: Lanes<A, L>,
    pub(super) z: Lanes<A, L>,
}

impl<A: Arith<L>, const L: usize> V3<A, L> {
    #[inline(always)]
    pub(super) fn splat(arith: A, x: f64) -> Self {
        let x = Lanes::splat(arith, x);
        Self { x, y: x, z: x }
    }

    #[inline(always)]
    pub(super) fn dot(self, o: Self) -> Lanes<A, L> {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    #[inline(always)]
    pub(super) fn cross(self, o: Self) -> Self {
        Self {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }

    #[inline(always)]
    pub(super) fn scale(self, s: Lanes<A, L>) -> Self {
        Self {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

impl<A: Regroup> V3<A, LANES> {
    /// Lane `j` is `f(j)`.
    #[inline(always)]
    pub(super) fn gather(arith: A, mut f: impl FnMut(usize) -> Vec3) -> Self {
        let v: [Vec3; LANES] = std::array::from_fn(&mut f);
        Self {
            x: Lanes::from_fn(arith, |j| v[j].x),
            y: Lanes::from_fn(arith, |j| v[j].y),
            z: Lanes::from_fn(arith, |j| v[j].z),
        }
    }

    /// Lane `j` is `block[j]` (a block of [`LANES`] consecutive voxels).
    #[inline(always)]
    pub(super) fn block(arith: A, block: &[Vec3]) -> Self {
        let [x, y, z] = load_columns3(arith, block);
        Self { x, y, z }
    }

    /// Lane `j` added to (or, `SUBTRACT`, taken from) `block[j]`.
    #[inline(always)]
    pub(super) fn add_to<const SUBTRACT: bool>(&self, block: &mut [Vec3]) {
        let arith = self.x.arith;
        let delta = arith.image3([self.x.v, self.y.v, self.z.v]);
        add_image3::<SUBTRACT, A>(arith, block, delta);
    }

    /// Every lane, as 3-vectors.
    #[inline(always)]
    pub(super) fn lanes(&self) -> [Vec3; LANES] {
        let (x, y, z) = (self.x.to_array(), self.y.to_array(), self.z.to_array());
        std::array::from_fn(|j| Vec3::new(x[j], y[j], z[j]))
    }
}

impl<A: Arith<L>, const L: usize> std::ops::Add for V3<A, L> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}
impl<A: Arith<L>, const L: usize> std::ops::Sub for V3<A, L> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

/// A rotation matrix per lane, by columns (see [`super::math::Mat3`]).
#[derive(Clone, Copy)]
pub(super) struct M3<A: Arith<L>, const L: usize> {
    pub(super) cx: V3<A, L>,
    pub(super) cy: V3<A, L>,
    pub(super) cz: V3<A, L>,
}

impl<A: Arith<L>, const L: usize> M3<A, L> {
    /// The rotation matrix of `q / |q|` given `s` = 2/|q|² (`q` as w, x, y, z).
    #[inline(always)]
    pub(super) fn from_quat(q: [Lanes<A, L>; 4], s: Lanes<A, L>) -> Self {
        let [w, x, y, z] = q;
        let (xx, yy, zz) = (x * x, y * y, z * z);
        let (xy, xz, yz) = (x * y, x * z, y * z);
        let (wx, wy, wz) = (w * x, w * y, w * z);
        let one = Lanes::splat(s.arith, 1.0);
        Self {
            cx: V3 {
                x: one - s * (yy + zz),
                y: s * (xy + wz),
                z: s * (xz - wy),
            },
            cy: V3 {
                x: s * (xy - wz),
                y: one - s * (xx + zz),
                z: s * (yz + wx),
            },
            cz: V3 {
                x: s * (xz + wy),
                y: s * (yz - wx),
                z: one - s * (xx + yy),
            },
        }
    }

    #[inline(always)]
    pub(super) fn apply(&self, v: V3<A, L>) -> V3<A, L> {
        self.cx.scale(v.x) + self.cy.scale(v.y) + self.cz.scale(v.z)
    }

    #[inline(always)]
    pub(super) fn apply_transpose(&self, v: V3<A, L>) -> V3<A, L> {
        V3 {
            x: self.cx.dot(v),
            y: self.cy.dot(v),
            z: self.cz.dot(v),
        }
    }
}

/// Where the rotation-vector series is accurate: tan²(angle/2) below this (NaN is not).
pub(super) const SERIES_LIMIT: f64 = 2.5e-3;

/// A quaternion per lane (w, x, y, z): lane `j` is `q[index(j)]`.
#[inline(always)]
pub(super) fn gather_quat<A: Regroup>(
    arith: A,
    q: &[Quat],
    index: impl Fn(usize) -> usize,
) -> [Lanes<A, LANES>; 4] {
    let v: [Quat; LANES] = std::array::from_fn(|j| q[index(j)]);
    [
        Lanes::from_fn(arith, |j| v[j].w),
        Lanes::from_fn(arith, |j| v[j].x),
        Lanes::from_fn(arith, |j| v[j].y),
        Lanes::from_fn(arith, |j| v[j].z),
    ]
}

/// Per lane, `a` where the link's axis (0, 1 or 2 as `f64`) is `k`, and `b` elsewhere.
#[inline(always)]
pub(super) fn on_axis<A: Arith<L>, const L: usize>(
    axis: Lanes<A, L>,
    k: f64,
    a: Lanes<A, L>,
    b: Lanes<A, L>,
) -> Lanes<A, L> {
    Lanes {
        v: axis.arith.select_eq(axis.v, A::E::of(k), a.v, b.v),
        arith: axis.arith,
    }
}

/// The vector (a on the link axis, b across it) per lane.
#[inline(always)]
pub(super) fn axial_split<A: Arith<L>, const L: usize>(
    axis: Lanes<A, L>,
    a: Lanes<A, L>,
    b: Lanes<A, L>,
) -> V3<A, L> {
    V3 {
        x: on_axis(axis, 0.0, a, b),
        y: on_axis(axis, 1.0, a, b),
        z: on_axis(axis, 2.0, a, b),
    }
}
