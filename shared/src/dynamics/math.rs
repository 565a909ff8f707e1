//! Small, inlined 3-vector and quaternion types for the hot loops. They are plain `Copy` structs
//! of `f64` so the state arrays stay flat and the compiler can keep everything in registers.

use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

use serde::{Deserialize, Serialize};

/// A 3-vector in metres, newtons, radians… whatever the variable name says.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Serialize,
    Deserialize,
    bytemuck::Pod,
    bytemuck::Zeroable,
)]
#[repr(C)]
pub struct Vec3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

impl Vec3 {
    pub const ZERO: Self = Self::new(0.0, 0.0, 0.0);

    #[inline(always)]
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }

    #[inline(always)]
    pub fn dot(self, o: Self) -> f64 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        Self::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }

    #[inline(always)]
    pub fn norm2(self) -> f64 {
        self.dot(self)
    }

    #[inline(always)]
    pub fn norm(self) -> f64 {
        self.norm2().sqrt()
    }

    /// Component `k` (0 = x, 1 = y, 2 = z).
    #[inline(always)]
    pub fn get(self, k: usize) -> f64 {
        match k {
            0 => self.x,
            1 => self.y,
            _ => self.z,
        }
    }

    /// The components cyclically shifted so that axis `k` comes first: a link along axis `k` is
    /// then handled as a link along x. Cyclic shifts keep the frame right-handed.
    #[inline(always)]
    pub fn to_axis(self, k: u8) -> Self {
        match k {
            0 => self,
            1 => Self::new(self.y, self.z, self.x),
            _ => Self::new(self.z, self.x, self.y),
        }
    }

    /// Inverse of [`Vec3::to_axis`].
    #[inline(always)]
    pub fn unshift_axis(self, k: u8) -> Self {
        match k {
            0 => self,
            1 => Self::new(self.z, self.x, self.y),
            _ => Self::new(self.y, self.z, self.x),
        }
    }
}

impl Add for Vec3 {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl Sub for Vec3 {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl Mul<f64> for Vec3 {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: f64) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
}
impl Neg for Vec3 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y, -self.z)
    }
}
impl AddAssign for Vec3 {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl SubAssign for Vec3 {
    #[inline(always)]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}

/// A rotation as a unit quaternion `w + xi + yj + zk`.
#[derive(
    Clone, Copy, Debug, PartialEq, Serialize, Deserialize, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(C)]
pub struct Quat {
    pub w: f64,
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

impl Default for Quat {
    fn default() -> Self {
        Self::IDENTITY
    }
}

/// A rotation matrix stored by columns: the world coordinates of a frame's x, y and z axes.
#[derive(Clone, Copy, Debug)]
pub struct Mat3 {
    pub cx: Vec3,
    pub cy: Vec3,
    pub cz: Vec3,
}

impl Mat3 {
    /// `R v`: a vector given in the frame, expressed in the world.
    #[inline(always)]
    pub fn apply(&self, v: Vec3) -> Vec3 {
        self.cx * v.x + self.cy * v.y + self.cz * v.z
    }

    /// `Rᵀ v`: a world vector expressed in the frame.
    #[inline(always)]
    pub fn apply_transpose(&self, v: Vec3) -> Vec3 {
        Vec3::new(self.cx.dot(v), self.cy.dot(v), self.cz.dot(v))
    }
}

impl Quat {
    pub const IDENTITY: Self = Self {
        w: 1.0,
        x: 0.0,
        y: 0.0,
        z: 0.0,
    };

    #[inline(always)]
    pub fn vector(self) -> Vec3 {
        Vec3::new(self.x, self.y, self.z)
    }

    #[inline(always)]
    pub fn conj(self) -> Self {
        Self {
            w: self.w,
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }

    #[inline(always)]
    pub fn compose(self, o: Self) -> Self {
        Self {
            w: self.w * o.w - self.x * o.x - self.y * o.y - self.z * o.z,
            x: self.w * o.x + self.x * o.w + self.y * o.z - self.z * o.y,
            y: self.w * o.y - self.x * o.z + self.y * o.w + self.z * o.x,
            z: self.w * o.z + self.x * o.y - self.y * o.x + self.z * o.w,
        }
    }

    #[inline(always)]
    pub fn norm2(self) -> f64 {
        self.w * self.w + self.x * self.x + self.y * self.y + self.z * self.z
    }

    #[inline(always)]
    pub fn scaled(self, s: f64) -> Self {
        Self {
            w: self.w * s,
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }

    #[inline(always)]
    pub fn normalized(self) -> Self {
        self.scaled(1.0 / self.norm2().sqrt())
    }

    /// The rotation by the rotation vector `theta` (axis times angle, rad).
    pub fn from_rotation_vector(theta: Vec3) -> Self {
        let angle = theta.norm();
        if angle < 1e-300 {
            return Self::IDENTITY;
        }
        let (s, c) = (0.5 * angle).sin_cos();
        let axis = theta * (s / angle);
        Self {
            w: c,
            x: axis.x,
            y: axis.y,
            z: axis.z,
        }
    }

    /// The rotation vector (axis times angle in (−π, π]) of this rotation; exact for large angles,
    /// a short series near zero where `atan2` would lose accuracy and time.
    #[inline(always)]
    pub fn rotation_vector(self) -> Vec3 {
        let q = if self.w < 0.0 {
            self.scaled(-1.0)
        } else {
            self
        };
        let s2 = q.x * q.x + q.y * q.y + q.z * q.z;
        let t2 = s2 / (q.w * q.w);
        // angle = 2 atan(s / w); 2 atan(t)/t = 2 (1 - t²/3 + t⁴/5 - t⁶/7 ...), truncation below
        // 1e-10 for t < 0.05 (rotations under ~6°, the common case between neighbouring voxels).
        let scale = if t2 < 2.5e-3 {
            2.0 / q.w * (1.0 - t2 * (1.0 / 3.0 - t2 * (0.2 - t2 * (1.0 / 7.0))))
        } else {
            let s = s2.sqrt();
            2.0 * s.atan2(q.w) / s
        };
        q.vector() * scale
    }

    /// `q v q*`: the vector rotated by this rotation.
    #[inline(always)]
    pub fn rotate(self, v: Vec3) -> Vec3 {
        let u = self.vector();
        let t = u.cross(v) * 2.0;
        v + t * self.w + u.cross(t)
    }

    /// The rotation matrix of a unit quaternion.
    #[inline(always)]
    pub fn to_matrix(self) -> Mat3 {
        self.to_matrix_with_scale(2.0)
    }

    /// The rotation matrix of `self / |self|` given `two_over_norm2` = 2/|self|²: a quaternion
    /// known only up to scale costs one division here instead of a square root and a division
    /// to normalise it first (the square root's latency dominated the link pass).
    #[inline(always)]
    pub fn to_matrix_with_scale(self, two_over_norm2: f64) -> Mat3 {
        let (w, x, y, z) = (self.w, self.x, self.y, self.z);
        let (xx, yy, zz) = (x * x, y * y, z * z);
        let (xy, xz, yz) = (x * y, x * z, y * z);
        let (wx, wy, wz) = (w * x, w * y, w * z);
        let s = two_over_norm2;
        Mat3 {
            cx: Vec3::new(1.0 - s * (yy + zz), s * (xy + wz), s * (xz - wy)),
            cy: Vec3::new(s * (xy - wz), 1.0 - s * (xx + zz), s * (yz + wx)),
            cz: Vec3::new(s * (xz + wy), s * (yz - wx), 1.0 - s * (xx + yy)),
        }
    }
}

#[cfg(test)]
mod tests;
