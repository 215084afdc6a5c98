//! The lane vectors of the batched coordinates kernels (MVC: [`super::mvc_batch`], Green:
//! [`super::green_batch`]): [`LANES`] f64 values per batch with element-wise operators (IEEE,
//! the same bits on every instruction set), per-lane masks, and the arithmetic that differs per
//! CPU ([`LaneMath`]: plain IEEE, FMA with IEEE division and square root, or AVX-512 estimates
//! refined by Newton steps; MVC's tiers each use their own).

#![cfg_attr(
    target_arch = "x86_64",
    expect(
        unsafe_code,
        reason = "AVX-512 intrinsics on the tiers that detected avx512f"
    )
)]

/// Points per batch.
pub(crate) const LANES: usize = 8;

pub(super) type Lanes = [f64; LANES];

/// An array of [`LANES`] values, `$e` evaluated with `$l` = 0, 1, …: a `while` loop in the
/// caller's body, with no closure and no call.
///
/// Why not `std::array::from_fn` or closures: the kernels are large functions, and LLVM did not
/// always inline the closures (and `from_fn`'s wrappers around them) into them. An out-of-line
/// closure is compiled without the kernel's `target_feature`s, so a fused multiply-add in it
/// became a call of libm's `fma` per lane, and an intrinsic a call per vector: the same MVC
/// kernel took 66–69 ms at 133k in one binary and 196–206 ms in another, Green's 133 or 284 ms,
/// depending only on how the crate was partitioned and inlined in that build (`perf` showed
/// `try_trait::Wrapped::call_mut`, `fma`, `_mm512_loadu_pd` as functions of their own).
/// A loop in an `#[inline(always)]` function has nothing left for the inliner to decline.
macro_rules! per_lane {
    ($zero:expr, |$l:ident| $e:expr) => {{
        let mut out = [$zero; LANES];
        let mut $l = 0;
        while $l < LANES {
            out[$l] = $e;
            $l += 1;
        }
        out
    }};
}
pub(super) use per_lane;

/// [`LANES`] f64 values, one per point of a batch; element-wise operators (each a single vector
/// instruction once inlined into a `target_feature` function; see [`per_lane`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct V8(pub(super) Lanes);

/// Per-lane booleans as all-ones / all-zeros 64-bit lanes (the form vector compares produce;
/// `[bool; 8]` makes LLVM shuffle bytes around).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Mask(pub(super) [u64; LANES]);

impl Mask {
    /// The mask of `f(l)` per lane. Takes a closure: for the code around the kernels' hot
    /// loops (per batch, not per face); the comparisons inside them are [`V8::gt`], [`V8::ge`].
    #[inline(always)]
    pub(super) fn from_fn(f: impl Fn(usize) -> bool) -> Self {
        Self(per_lane!(0, |l| if f(l) { u64::MAX } else { 0 }))
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
    /// IEEE square root per lane.
    #[inline(always)]
    pub(super) fn sqrt(self) -> Self {
        Self(per_lane!(0.0, |l| self.0[l].sqrt()))
    }
    #[inline(always)]
    pub(super) fn abs(self) -> Self {
        Self(per_lane!(0.0, |l| self.0[l].abs()))
    }
    #[inline(always)]
    pub(super) fn min(self, other: Self) -> Self {
        Self(per_lane!(0.0, |l| if other.0[l] < self.0[l] {
            other.0[l]
        } else {
            self.0[l]
        }))
    }
    #[inline(always)]
    pub(super) fn max(self, other: Self) -> Self {
        Self(per_lane!(0.0, |l| if other.0[l] > self.0[l] {
            other.0[l]
        } else {
            self.0[l]
        }))
    }
    /// `self > other` per lane.
    #[inline(always)]
    pub(super) fn gt(self, other: Self) -> Mask {
        Mask(per_lane!(0, |l| if self.0[l] > other.0[l] {
            u64::MAX
        } else {
            0
        }))
    }
    /// `self >= other` per lane (false for NaN).
    #[inline(always)]
    pub(super) fn ge(self, other: Self) -> Mask {
        Mask(per_lane!(0, |l| if self.0[l] >= other.0[l] {
            u64::MAX
        } else {
            0
        }))
    }
    /// `if mask { a } else { b }` per lane.
    #[inline(always)]
    pub(super) fn select(mask: Mask, a: Self, b: Self) -> Self {
        Self(per_lane!(0.0, |l| if mask.test(l) {
            a.0[l]
        } else {
            b.0[l]
        }))
    }
}

/// The element-wise binary operators of [`V8`], each a [`per_lane`] loop.
macro_rules! lane_operator {
    ($trait:ident, $method:ident, $op:tt) => {
        impl std::ops::$trait for V8 {
            type Output = Self;
            #[inline(always)]
            fn $method(self, other: Self) -> Self {
                Self(per_lane!(0.0, |l| self.0[l] $op other.0[l]))
            }
        }
    };
}
lane_operator!(Add, add, +);
lane_operator!(Sub, sub, -);
lane_operator!(Mul, mul, *);
lane_operator!(Div, div, /);

impl std::ops::Mul<f64> for V8 {
    type Output = Self;
    #[inline(always)]
    fn mul(self, other: f64) -> Self {
        Self(per_lane!(0.0, |l| self.0[l] * other))
    }
}

impl std::ops::Neg for V8 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self(per_lane!(0.0, |l| -self.0[l]))
    }
}

/// Per-lane `a | b`.
#[inline(always)]
pub(super) fn or(a: Mask, b: Mask) -> Mask {
    Mask(per_lane!(0, |l| a.0[l] | b.0[l]))
}

/// Per-lane `!a`.
#[inline(always)]
pub(super) fn not(a: Mask) -> Mask {
    Mask(per_lane!(0, |l| !a.0[l]))
}

/// Element-wise arithmetic whose fastest form depends on the instruction set.
pub(super) trait LaneMath {
    /// `a · b + c` (fused where the target has FMA).
    fn mul_add(a: V8, b: V8, c: V8) -> V8;
    /// `1 / x` per lane (to about 1 ulp).
    fn recip(x: V8) -> V8;
    /// `1 / √x` per lane (to about 1 ulp).
    fn rsqrt(x: V8) -> V8;
    /// The significand in [1, 2) and the unbiased binary exponent (as an f64, exactly) of each
    /// lane of `x`, for positive normal numbers (other lanes give garbage): exact, the same bits
    /// on every tier ([`super::lane_functions::significand_and_exponent`], bit operations, or
    /// AVX-512's `vgetmantpd` / `vgetexppd`).
    #[inline(always)]
    fn significand_and_exponent(x: V8) -> (V8, V8) {
        super::lane_functions::significand_and_exponent(x)
    }
}

/// `a · b` per lane, for vectors as (x, y, z) lanes: `a₀b₀ + (a₁b₁ + a₂b₂)` with `M`'s
/// multiply-add (a function, not a closure: see [`per_lane`]).
#[inline(always)]
pub(super) fn dot<M: LaneMath>(a: &[V8; 3], b: &[V8; 3]) -> V8 {
    M::mul_add(a[0], b[0], M::mul_add(a[1], b[1], a[2] * b[2]))
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
        V8(per_lane!(0.0, |l| 1.0 / x.0[l]))
    }
    #[inline(always)]
    fn rsqrt(x: V8) -> V8 {
        V8(per_lane!(0.0, |l| 1.0 / x.0[l].sqrt()))
    }
}

/// FMA with IEEE division and square root (AVX2 + FMA).
#[cfg(target_arch = "x86_64")]
pub(super) struct FusedMath;

#[cfg(target_arch = "x86_64")]
impl LaneMath for FusedMath {
    /// `f64::mul_add` per lane ([`per_lane`]): one `vfmadd` once inlined into a tier with FMA.
    #[inline(always)]
    fn mul_add(a: V8, b: V8, c: V8) -> V8 {
        V8(per_lane!(0.0, |l| a.0[l].mul_add(b.0[l], c.0[l])))
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
        use std::arch::x86_64::{
            _mm512_fmadd_pd, _mm512_fnmadd_pd, _mm512_loadu_pd, _mm512_rcp14_pd, _mm512_set1_pd,
            _mm512_storeu_pd,
        };
        const { assert!(LANES == 8) };
        let mut out = V8::splat(0.0);
        // SAFETY: only reached from the AVX-512 tiers (`evaluate_rows_avx512`,
        // `evaluate_green_rows_avx512`), after `avx512f` was detected; the loads/stores cover
        // exactly the 8 lanes.
        unsafe {
            let v = _mm512_loadu_pd(x.0.as_ptr());
            let one = _mm512_set1_pd(1.0);
            // Two Newton steps y ← y + y (1 − v y), written out (no loop to inline).
            let y = _mm512_rcp14_pd(v);
            let y = _mm512_fmadd_pd(y, _mm512_fnmadd_pd(v, y, one), y);
            let y = _mm512_fmadd_pd(y, _mm512_fnmadd_pd(v, y, one), y);
            _mm512_storeu_pd(out.0.as_mut_ptr(), y);
        }
        out
    }
    /// `vgetmantpd` (interval [1, 2), the source's sign) and `vgetexppd`: two instructions
    /// instead of five bit operations per number.
    #[inline(always)]
    fn significand_and_exponent(x: V8) -> (V8, V8) {
        use std::arch::x86_64::{
            _MM_MANT_NORM_1_2, _MM_MANT_SIGN_SRC, _mm512_getexp_pd, _mm512_getmant_pd,
            _mm512_loadu_pd, _mm512_storeu_pd,
        };
        let (mut significand, mut exponent) = (V8::splat(0.0), V8::splat(0.0));
        // SAFETY: as in `recip`.
        unsafe {
            let v = _mm512_loadu_pd(x.0.as_ptr());
            let m = _mm512_getmant_pd::<_MM_MANT_NORM_1_2, _MM_MANT_SIGN_SRC>(v);
            _mm512_storeu_pd(significand.0.as_mut_ptr(), m);
            _mm512_storeu_pd(exponent.0.as_mut_ptr(), _mm512_getexp_pd(v));
        }
        (significand, exponent)
    }
    #[inline(always)]
    fn rsqrt(x: V8) -> V8 {
        use std::arch::x86_64::{
            _mm512_fmadd_pd, _mm512_fnmadd_pd, _mm512_loadu_pd, _mm512_mul_pd, _mm512_rsqrt14_pd,
            _mm512_set1_pd, _mm512_storeu_pd,
        };
        let mut out = V8::splat(0.0);
        // SAFETY: as in `recip`.
        unsafe {
            let v = _mm512_loadu_pd(x.0.as_ptr());
            let half_v = _mm512_mul_pd(v, _mm512_set1_pd(0.5));
            let half = _mm512_set1_pd(0.5);
            // Two Newton steps y ← y + y (½ − ½ v y²), written out.
            let y = _mm512_rsqrt14_pd(v);
            let y = _mm512_fmadd_pd(y, _mm512_fnmadd_pd(_mm512_mul_pd(half_v, y), y, half), y);
            let y = _mm512_fmadd_pd(y, _mm512_fnmadd_pd(_mm512_mul_pd(half_v, y), y, half), y);
            _mm512_storeu_pd(out.0.as_mut_ptr(), y);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    /// The text of the first `fn {name}` of `source` (not in its test module), up to its closing
    /// brace in column 0.
    fn body<'a>(source: &'a str, name: &str) -> &'a str {
        let source = source
            .split("\n#[cfg(test)]\nmod tests")
            .next()
            .unwrap_or(source);
        let start = [
            format!("\nfn {name}<"),
            format!("\nfn {name}("),
            format!(" fn {name}<"),
            format!(" fn {name}("),
        ]
        .iter()
        .filter_map(|pattern| source.find(pattern.as_str()))
        .min()
        .unwrap_or_else(|| panic!("no fn {name}"));
        let end = source[start..]
            .find("\n}\n")
            .map_or(source.len(), |e| start + e);
        &source[start..end]
    }

    /// The kernels' per-batch and per-face code (and the exact path's column products) takes no
    /// closure, `array::from_fn` or array `map` (see [`per_lane`](super::per_lane)): where LLVM
    /// left such a closure out of line, its arithmetic lost the kernel's instruction set (a call
    /// of libm's `fma` per lane), and the MVC binding at 133k took 196–206 ms instead of 66–69 ms.
    #[test]
    fn the_kernels_hot_code_takes_no_closures() {
        let kernels: [(&str, &str, &[&str]); 5] = [
            (
                "coords/mvc_lanes.rs",
                include_str!("mvc_lanes.rs"),
                &["dot"],
            ),
            (
                "cage_coords/column_products.rs",
                include_str!("../cage_coords/column_products.rs"),
                &[
                    "add_columns_generic",
                    "rows_of_columns_generic",
                    "add_group_to_rows",
                    "add_group",
                ],
            ),
            (
                "mvc_batch.rs",
                include_str!("mvc_batch.rs"),
                &["evaluate_batch"],
            ),
            (
                "green_batch.rs",
                include_str!("green_batch.rs"),
                &[
                    "evaluate_batch",
                    "dot_constant",
                    "inverse_power_of_two",
                    "edge_integral",
                ],
            ),
            (
                "lane_functions.rs",
                include_str!("lane_functions.rs"),
                &[
                    "angle_fraction",
                    "significand_and_exponent",
                    "ln_of_quotient",
                ],
            ),
        ];
        for (file, source, functions) in kernels {
            for name in functions {
                let text = body(source, name);
                for pattern in ["from_fn(", ".map(|", "= |", "(|", "move |"] {
                    assert!(
                        !text.contains(pattern),
                        "{file}: fn {name} contains `{pattern}`"
                    );
                }
            }
        }
    }
}
