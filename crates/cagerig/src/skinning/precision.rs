//! The floating-point precision of a per-frame skinning kernel: one kernel body, written once
//! over [`SkinReal`], is compiled for `f64` (the exact path: glam `DVec3`/`DQuat`) and for `f32`
//! (the display path: SSE-width glam `Vec3A`/`Quat`, output packed to `Vec3`).
//!
//! Only the operations the kernels use are exposed. Neither instantiation uses fused
//! multiply-add, so a kernel gives the same bits on every code path (generic or AVX2).

use std::ops::{Add, Mul, Sub};

use glam::{DAffine3, DQuat, DVec3, Quat, Vec3, Vec3A};

/// A scalar type of the skinning kernels (`f32` or `f64`) and its vector, quaternion and output
/// types.
pub trait SkinReal:
    Copy
    + Send
    + Sync
    + Default
    + PartialEq
    + std::fmt::Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + 'static
{
    /// 3-vector used inside the kernels (`Vec3A` / `DVec3`).
    type V3: Copy
        + Send
        + Sync
        + std::fmt::Debug
        + Add<Output = Self::V3>
        + Sub<Output = Self::V3>
        + Mul<Self, Output = Self::V3>;
    /// Quaternion `(x, y, z, w)`, not necessarily unit (`Quat` / `DQuat`).
    type Quat: Copy
        + Send
        + Sync
        + std::fmt::Debug
        + Add<Output = Self::Quat>
        + Mul<Self, Output = Self::Quat>;
    /// Stored output point (`Vec3` / `DVec3`).
    type Out: Copy + Send + Sync;

    /// `0`.
    const ZERO: Self;
    /// `1`.
    const ONE: Self;
    /// `2`.
    const TWO: Self;
    /// The zero vector.
    const ZERO_V3: Self::V3;
    /// The zero quaternion `(0, 0, 0, 0)` (an accumulator, not a rotation).
    const ZERO_QUAT: Self::Quat;

    /// `x` rounded to this precision.
    fn from_f64(x: f64) -> Self;
    /// `1 / self`.
    fn recip(self) -> Self;
    /// `|self|` with the sign of `sign`.
    fn copysign(self, sign: Self) -> Self;
    /// `v` rounded to this precision.
    fn vec3(v: DVec3) -> Self::V3;
    /// `q` rounded to this precision.
    fn quat(q: DQuat) -> Self::Quat;
    /// Dot product `a · b`.
    fn dot(a: Self::V3, b: Self::V3) -> Self;
    /// Cross product `a × b`.
    fn cross(a: Self::V3, b: Self::V3) -> Self::V3;
    /// `[x, y, z]`.
    fn components(v: Self::V3) -> [Self; 3];
    /// Four-component dot product of two quaternions.
    fn quat_dot(a: Self::Quat, b: Self::Quat) -> Self;
    /// Vector part `(x, y, z)` and scalar part `w`.
    fn quat_parts(q: Self::Quat) -> (Self::V3, Self);
    /// `[x, y, z, w]`.
    fn quat_array(q: Self::Quat) -> [Self; 4];
    /// The vector `(x, y, z)`.
    fn new_v3(x: Self, y: Self, z: Self) -> Self::V3;
    /// `v` as a stored output point (`Vec3` / `DVec3`).
    fn output(v: Self::V3) -> Self::Out;

    /// Columns `[x_axis, y_axis, z_axis, translation]` of an affine map, rounded.
    fn affine_columns(a: &DAffine3) -> [Self::V3; 4] {
        [
            Self::vec3(a.matrix3.x_axis),
            Self::vec3(a.matrix3.y_axis),
            Self::vec3(a.matrix3.z_axis),
            Self::vec3(a.translation),
        ]
    }

    /// `|v|²`.
    #[inline(always)]
    fn length_squared(v: Self::V3) -> Self {
        Self::dot(v, v)
    }
}

macro_rules! impl_skin_real {
    ($scalar:ty, $v3:ty, $quat:ty, $out:ty, $vec3:expr, $quat_from:expr, $output:expr) => {
        impl SkinReal for $scalar {
            type V3 = $v3;
            type Quat = $quat;
            type Out = $out;

            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const TWO: Self = 2.0;
            const ZERO_V3: $v3 = <$v3>::ZERO;
            const ZERO_QUAT: $quat = <$quat>::from_xyzw(0.0, 0.0, 0.0, 0.0);

            #[inline(always)]
            fn from_f64(x: f64) -> Self {
                x as $scalar
            }
            #[inline(always)]
            fn recip(self) -> Self {
                1.0 / self
            }
            #[inline(always)]
            fn copysign(self, sign: Self) -> Self {
                <$scalar>::copysign(self, sign)
            }
            #[inline(always)]
            fn vec3(v: DVec3) -> $v3 {
                $vec3(v)
            }
            #[inline(always)]
            fn quat(q: DQuat) -> $quat {
                $quat_from(q)
            }
            #[inline(always)]
            fn dot(a: $v3, b: $v3) -> Self {
                a.dot(b)
            }
            #[inline(always)]
            fn cross(a: $v3, b: $v3) -> $v3 {
                a.cross(b)
            }
            #[inline(always)]
            fn components(v: $v3) -> [Self; 3] {
                [v.x, v.y, v.z]
            }
            #[inline(always)]
            fn quat_dot(a: $quat, b: $quat) -> Self {
                a.dot(b)
            }
            #[inline(always)]
            fn quat_parts(q: $quat) -> ($v3, Self) {
                (<$v3>::new(q.x, q.y, q.z), q.w)
            }
            #[inline(always)]
            fn quat_array(q: $quat) -> [Self; 4] {
                q.to_array()
            }
            #[inline(always)]
            fn new_v3(x: Self, y: Self, z: Self) -> $v3 {
                <$v3>::new(x, y, z)
            }
            #[inline(always)]
            fn output(v: $v3) -> $out {
                $output(v)
            }
        }
    };
}

impl_skin_real!(
    f64,
    DVec3,
    DQuat,
    DVec3,
    |v: DVec3| v,
    |q: DQuat| q,
    |v: DVec3| v
);
impl_skin_real!(
    f32,
    Vec3A,
    Quat,
    Vec3,
    |v: DVec3| Vec3A::from(v.as_vec3()),
    |q: DQuat| q.as_quat(),
    Vec3::from
);

/// A rest position handed to the f32 kernels: f64 (the exact M), or f32 (the display path's
/// M̃ = Φ̃·C), read exactly as f64.
pub trait RestPoint: Copy + Send + Sync {
    /// The point as f64 (exact: f32 widens without rounding).
    fn to_f64(self) -> glam::DVec3;
}

impl RestPoint for glam::DVec3 {
    #[inline(always)]
    fn to_f64(self) -> glam::DVec3 {
        self
    }
}

impl RestPoint for glam::Vec3 {
    #[inline(always)]
    fn to_f64(self) -> glam::DVec3 {
        self.as_dvec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn exercise<S: SkinReal>() -> ([S; 3], S, S, [S; 3]) {
        let a = S::vec3(DVec3::new(1.0, 2.0, 3.0));
        let b = S::vec3(DVec3::new(-2.0, 0.5, 4.0));
        let q = S::quat(DQuat::from_xyzw(0.5, -0.5, 0.5, 0.5));
        let (v, w) = S::quat_parts(q + q * S::ONE);
        (
            S::components(S::cross(a, b)),
            S::dot(a, b),
            S::quat_dot(q, q) + w,
            S::components(v),
        )
    }

    #[test]
    fn both_precisions_give_the_same_small_integer_results() {
        let (cross, dot, qq, v) = exercise::<f64>();
        assert_eq!(cross, [6.5, -10.0, 4.5]);
        assert_eq!(dot, 11.0);
        assert_eq!(qq, 2.0);
        assert_eq!(v, [1.0, -1.0, 1.0]);
        let (cross, dot, qq, v) = exercise::<f32>();
        assert_eq!(cross, [6.5, -10.0, 4.5]);
        assert_eq!(dot, 11.0);
        assert_eq!(qq, 2.0);
        assert_eq!(v, [1.0, -1.0, 1.0]);
        assert_eq!(2.0f32.copysign(-0.0), -2.0);
        assert_eq!(<f64 as SkinReal>::recip(4.0), 0.25);
    }
}
