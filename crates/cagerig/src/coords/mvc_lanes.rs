//! The lane vectors of the batched coordinates kernels (MVC: [`super::mvc_batch`], Green:
//! [`super::green_batch`]): [`LANES`] f64 values per batch with element-wise operators (IEEE,
//! the same bits on every instruction set), per-lane masks, and the arithmetic that differs per
//! CPU ([`LaneMath`]: plain IEEE, FMA with IEEE division and square root, or AVX-512 estimates
//! refined by Newton steps; MVC's tiers each use their own).

/// Points per batch.
pub(crate) const LANES: usize = 8;

pub(super) type Lanes = [f64; LANES];

/// [`LANES`] f64 values, one per point of a batch; element-wise operators (each a single vector
/// instruction once inlined into a `target_feature` function).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct V8(pub(super) Lanes);

/// Per-lane booleans as all-ones / all-zeros 64-bit lanes (the form vector compares produce;
/// `[bool; 8]` makes LLVM shuffle bytes around).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Mask(pub(super) [u64; LANES]);

impl Mask {
    #[inline(always)]
    pub(super) fn from_fn(f: impl Fn(usize) -> bool) -> Self {
        Self(std::array::from_fn(|l| if f(l) { u64::MAX } else { 0 }))
    }
    #[inline(always)]
    pub(super) fn test(self, l: usize) -> bool {
        self.0[l] != 0
    }
}

impl V8 {
    #[inline(always)]
    pub(super) fn splat(value: f64) -> Self {
        Self([value; LANES])
    }
    #[inline(always)]
    pub(super) fn map(self, f: impl Fn(f64) -> f64) -> Self {
        Self(std::array::from_fn(|l| f(self.0[l])))
    }
    #[inline(always)]
    pub(super) fn zip(self, other: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        Self(std::array::from_fn(|l| f(self.0[l], other.0[l])))
    }
    /// IEEE square root per lane.
    #[inline(always)]
    pub(super) fn sqrt(self) -> Self {
        self.map(f64::sqrt)
    }
    #[inline(always)]
    pub(super) fn abs(self) -> Self {
        self.map(f64::abs)
    }
    #[inline(always)]
    pub(super) fn min(self, other: Self) -> Self {
        self.zip(other, |a, b| if b < a { b } else { a })
    }
    #[inline(always)]
    pub(super) fn max(self, other: Self) -> Self {
        self.zip(other, |a, b| if b > a { b } else { a })
    }
    /// `self > other` per lane.
    #[inline(always)]
    pub(super) fn gt(self, other: Self) -> Mask {
        Mask::from_fn(|l| self.0[l] > other.0[l])
    }
    /// `self >= other` per lane (false for NaN).
    #[inline(always)]
    pub(super) fn ge(self, other: Self) -> Mask {
        Mask::from_fn(|l| self.0[l] >= other.0[l])
    }
    /// `if mask { a } else { b }` per lane.
    #[inline(always)]
    pub(super) fn select(mask: Mask, a: Self, b: Self) -> Self {
        Self(std::array::from_fn(|l| {
            if mask.test(l) { a.0[l] } else { b.0[l] }
        }))
    }
}

impl std::ops::Add for V8 {
    type Output = Self;
    #[inline(always)]
    fn add(self, other: Self) -> Self {
        self.zip(other, |a, b| a + b)
    }
}

impl std::ops::Sub for V8 {
    type Output = Self;
    #[inline(always)]
    fn sub(self, other: Self) -> Self {
        self.zip(other, |a, b| a - b)
    }
}

impl std::ops::Mul for V8 {
    type Output = Self;
    #[inline(always)]
    fn mul(self, other: Self) -> Self {
        self.zip(other, |a, b| a * b)
    }
}

impl std::ops::Div for V8 {
    type Output = Self;
    #[inline(always)]
    fn div(self, other: Self) -> Self {
        self.zip(other, |a, b| a / b)
    }
}

impl std::ops::Mul<f64> for V8 {
    type Output = Self;
    #[inline(always)]
    fn mul(self, other: f64) -> Self {
        self.map(|a| a * other)
    }
}

impl std::ops::Neg for V8 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        self.map(|a| -a)
    }
}

/// Per-lane `a | b`.
#[inline(always)]
pub(super) fn or(a: Mask, b: Mask) -> Mask {
    Mask(std::array::from_fn(|l| a.0[l] | b.0[l]))
}

/// Per-lane `!a`.
#[inline(always)]
pub(super) fn not(a: Mask) -> Mask {
    Mask(a.0.map(|x| !x))
}

/// Element-wise arithmetic whose fastest form depends on the instruction set.
pub(super) trait LaneMath {
    /// `a · b + c` (fused where the target has FMA).
    fn mul_add(a: V8, b: V8, c: V8) -> V8;
    /// `1 / x` per lane (to about 1 ulp).
    fn recip(x: V8) -> V8;
    /// `1 / √x` per lane (to about 1 ulp).
    fn rsqrt(x: V8) -> V8;
}

/// Plain IEEE operations (no FMA: `mul_add` would be a libm call).
pub(super) struct PlainMath;

impl LaneMath for PlainMath {
    #[inline(always)]
    fn mul_add(a: V8, b: V8, c: V8) -> V8 {
        a * b + c
    }
    #[inline(always)]
    fn recip(x: V8) -> V8 {
        x.map(|v| 1.0 / v)
    }
    #[inline(always)]
    fn rsqrt(x: V8) -> V8 {
        x.map(|v| 1.0 / v.sqrt())
    }
}

/// FMA with IEEE division and square root (AVX2 + FMA).
#[cfg(target_arch = "x86_64")]
pub(super) struct FusedMath;

#[cfg(target_arch = "x86_64")]
impl LaneMath for FusedMath {
    #[inline(always)]
    fn mul_add(a: V8, b: V8, c: V8) -> V8 {
        V8(std::array::from_fn(|l| a.0[l].mul_add(b.0[l], c.0[l])))
    }
    #[inline(always)]
    fn recip(x: V8) -> V8 {
        PlainMath::recip(x)
    }
    #[inline(always)]
    fn rsqrt(x: V8) -> V8 {
        PlainMath::rsqrt(x)
    }
}

/// AVX-512: FMA, and `vrcp14pd` / `vrsqrt14pd` estimates (relative error < 2⁻¹⁴) refined by two
/// Newton steps (error ≈ 2⁻⁵⁶ plus rounding). Only instantiated inside
/// `#[target_feature(enable = "avx512f")]` functions reached after runtime detection.
#[cfg(target_arch = "x86_64")]
pub(super) struct Avx512Math;

#[cfg(target_arch = "x86_64")]
impl LaneMath for Avx512Math {
    #[inline(always)]
    fn mul_add(a: V8, b: V8, c: V8) -> V8 {
        FusedMath::mul_add(a, b, c)
    }
    #[inline(always)]
    fn recip(x: V8) -> V8 {
        use std::arch::x86_64::*;
        const { assert!(LANES == 8) };
        let mut out = V8::splat(0.0);
        // SAFETY: only reached from `evaluate_rows_avx512`, after `avx512f` was detected; the
        // loads/stores cover exactly the 8 lanes.
        unsafe {
            let v = _mm512_loadu_pd(x.0.as_ptr());
            let one = _mm512_set1_pd(1.0);
            let mut y = _mm512_rcp14_pd(v);
            for _ in 0..2 {
                // y ← y + y (1 − v y)
                let e = _mm512_fnmadd_pd(v, y, one);
                y = _mm512_fmadd_pd(y, e, y);
            }
            _mm512_storeu_pd(out.0.as_mut_ptr(), y);
        }
        out
    }
    #[inline(always)]
    fn rsqrt(x: V8) -> V8 {
        use std::arch::x86_64::*;
        let mut out = V8::splat(0.0);
        // SAFETY: as in `recip`.
        unsafe {
            let v = _mm512_loadu_pd(x.0.as_ptr());
            let half_v = _mm512_mul_pd(v, _mm512_set1_pd(0.5));
            let half = _mm512_set1_pd(0.5);
            let mut y = _mm512_rsqrt14_pd(v);
            for _ in 0..2 {
                // y ← y + y (½ − ½ v y²)
                let e = _mm512_fnmadd_pd(_mm512_mul_pd(half_v, y), y, half);
                y = _mm512_fmadd_pd(y, e, y);
            }
            _mm512_storeu_pd(out.0.as_mut_ptr(), y);
        }
        out
    }
}
