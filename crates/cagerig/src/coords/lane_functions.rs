//! Elementary functions over lanes ([`V8`]) for the batched coordinates kernels: the arctangent
//! as a fraction ([`angle_fraction`]: MVC's edge angles, Green's solid angles) and the natural
//! logarithm of a quotient ([`ln_of_quotient`]: Green's edge integrals). Branch-free (selects
//! only), so that every lane of a batch runs the same instructions, and with no division of
//! their own beyond the one reciprocal in [`ln_of_quotient`].

use super::mvc_lanes::{LANES, LaneMath, V8, per_lane};

/// Cephes `atan` coefficients: atan x = x + x·z·P(z)/Q(z), z = x², |x| ≤ 0.66.
const ATAN_P: [f64; 5] = [
    -8.750_608_600_031_904e-1,
    -1.615_753_718_733_365e1,
    -7.500_855_792_314_705e1,
    -1.228_866_684_490_136e2,
    -6.485_021_904_942_025e1,
];
const ATAN_Q: [f64; 5] = [
    2.485_846_490_142_306e1,
    1.650_270_098_316_988_5e2,
    4.328_810_604_912_903e2,
    4.853_903_996_359_137e2,
    1.945_506_571_482_614e2,
];
/// Low part of π/2 (π/2 = FRAC_PI_2 + this, to ~1e-33).
const FRAC_PI_2_LOW: f64 = 6.123_233_995_736_766e-17;

/// θ = atan2(sin, cos) ∈ [0, π] as a fraction `(numerator, denominator)`, for the sine and
/// cosine of an angle (`sin ≥ 0`; any common positive scale of the two, as long as the tenth
/// power of the larger stays a normal number: the fraction is homogeneous of degree 0; both zero
/// gives garbage, never a trap). Branch-free (selects only), no division: the Cephes reduction of
/// t = sin/|cos| to x = num/den ∈ {t, (t−1)/(t+1), −1/t} (|x| ≤ 0.66, den ∈ [0.8, 2]) and the
/// rational approximation atan x = x + x·z·P(z)/Q(z), z = x², written homogeneously in
/// (num, den): atan x = num·(Q̃ + num²·P̃) / (den·Q̃) with P̃ = den⁸ P(z), Q̃ = den¹⁰ Q(z).
/// Relative error a few ulp.
#[inline(always)]
pub(super) fn angle_fraction<M: LaneMath>(sin: V8, cos: V8) -> (V8, V8) {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let abs_cos = cos.abs();
    let big = sin.gt(abs_cos * 2.414_213_562_373_095);
    let mid = sin.gt(abs_cos * 0.66);
    let splat = V8::splat;
    let num = V8::select(big, -abs_cos, V8::select(mid, sin - abs_cos, sin));
    let den = V8::select(big, sin, V8::select(mid, sin + abs_cos, abs_cos));
    let base = V8::select(
        big,
        splat(FRAC_PI_2),
        V8::select(mid, splat(FRAC_PI_4), splat(0.0)),
    );
    let low = V8::select(
        big,
        splat(FRAC_PI_2_LOW),
        V8::select(mid, splat(0.5 * FRAC_PI_2_LOW), splat(0.0)),
    );
    // θ = base + atan x (cos ≥ 0) or π − base − atan x (cos < 0).
    let negative = splat(0.0).gt(cos);
    let signed_num = V8::select(negative, -num, num);
    let offset = V8::select(negative, (splat(PI) - base) - low, base + low);
    let (n2, d2) = (num * num, den * den);
    let d4 = d2 * d2;
    let (d6, d8) = (d4 * d2, d4 * d4);
    let p = M::mul_add(splat(ATAN_P[0]), n2, d2 * ATAN_P[1]);
    let p = M::mul_add(p, n2, d4 * ATAN_P[2]);
    let p = M::mul_add(p, n2, d6 * ATAN_P[3]);
    let p = M::mul_add(p, n2, d8 * ATAN_P[4]);
    let q = M::mul_add(splat(ATAN_Q[0]), d2, n2);
    let q = M::mul_add(q, n2, d4 * ATAN_Q[1]);
    let q = M::mul_add(q, n2, d6 * ATAN_Q[2]);
    let q = M::mul_add(q, n2, d8 * ATAN_Q[3]);
    let q = M::mul_add(q, n2, (d8 * d2) * ATAN_Q[4]);
    let den_q = den * q;
    let theta_times_den_q = M::mul_add(offset, den_q, signed_num * M::mul_add(n2, p, q));
    (theta_times_den_q, den_q)
}

/// fdlibm's minimax coefficients for `ln((1 + s)/(1 − s)) = 2s + s·R(z)`, z = s², |s| ≤ 0.1716
/// (error of R below 2⁻⁵⁸·⁴⁵): `R(z) = Σ_j LN_COEFFICIENTS[j] z^(j+1)`.
const LN_COEFFICIENTS: [f64; 7] = [
    6.666_666_666_666_735e-1,
    3.999_999_999_940_942e-1,
    2.857_142_874_366_239e-1,
    2.222_219_843_214_978_4e-1,
    1.818_357_216_161_805e-1,
    1.531_383_769_920_937_3e-1,
    1.479_819_860_511_658_6e-1,
];
/// ln 2 split so that `k · LN_2_HIGH` is exact for |k| < 2¹¹ (fdlibm's `ln2_hi`, `ln2_lo`).
const LN_2_HIGH: f64 = 6.931_471_803_691_238e-1;
const LN_2_LOW: f64 = 1.908_214_929_270_587_7e-10;

/// The significand in [1, 2) and the unbiased binary exponent (as an f64, exactly) of each lane
/// of `x` (positive normal numbers; other lanes give garbage): bit operations only.
#[inline(always)]
pub(super) fn significand_and_exponent(x: V8) -> (V8, V8) {
    const SIGNIFICAND: u64 = (1 << 52) - 1;
    const ONE: u64 = 0x3ff0_0000_0000_0000;
    // 2⁵² + b as bits is the f64 2⁵² + b for b < 2⁵²: the biased exponent b without an
    // integer-to-float conversion (which AVX2 lacks for 64-bit lanes).
    const TWO_TO_52: u64 = 0x4330_0000_0000_0000;
    let bits: [u64; LANES] = per_lane!(0, |l| x.0[l].to_bits());
    let significand = V8(per_lane!(0.0, |l| f64::from_bits(
        (bits[l] & SIGNIFICAND) | ONE
    )));
    let exponent = V8(per_lane!(0.0, |l| f64::from_bits(
        (bits[l] >> 52) | TWO_TO_52
    ) - (4_503_599_627_370_496.0 + 1023.0)));
    (significand, exponent)
}

/// `ln(num / den)` per lane, for positive normal `num` and `den` (other lanes give garbage or
/// NaN, never a trap), without forming the quotient (so it cannot overflow): with
/// `num = a·2^p`, `den = b·2^q` (a, b ∈ [1, 2)) scaled by 2 so that a/b ∈ [1/√2, √2], and
/// `s = (a − b)/(a + b)` (a − b exact), `ln(num/den) = (p − q) ln 2 + 2s + s·R(s²)` (fdlibm's
/// polynomial, by Horner's rule: Estrin's scheme measured slower in Green's kernel). One
/// reciprocal (`M::recip`: a division, or AVX-512's estimate refined to about an ulp) and the
/// products fused where `M` fuses; error within about 2 ulp of the result plus 2 ulp of
/// `|p − q| ln 2` (tested with plain IEEE; the kernels' tier tests bound the others).
#[inline(always)]
pub(super) fn ln_of_quotient<M: LaneMath>(num: V8, den: V8) -> V8 {
    use std::f64::consts::SQRT_2;
    let (a, p) = M::significand_and_exponent(num);
    let (b, q) = M::significand_and_exponent(den);
    let exponent = p - q;
    let high = a.gt(b * SQRT_2);
    let low = b.gt(a * SQRT_2);
    let b = V8::select(high, b * 2.0, b);
    let a = V8::select(low, a * 2.0, a);
    let exponent = V8::select(
        high,
        exponent + V8::splat(1.0),
        V8::select(low, exponent - V8::splat(1.0), exponent),
    );
    let s = (a - b) * M::recip(a + b);
    let z = s * s;
    let mut r = V8::splat(LN_COEFFICIENTS[6]);
    for &c in LN_COEFFICIENTS[..6].iter().rev() {
        r = M::mul_add(r, z, V8::splat(c));
    }
    let r = r * z;
    M::mul_add(
        exponent,
        V8::splat(LN_2_HIGH),
        M::mul_add(s, r, s * 2.0) + exponent * LN_2_LOW,
    )
}

#[cfg(test)]
#[expect(
    unsafe_code,
    reason = "the tests compare each lane-function tier with the scalar one"
)]
mod tests {
    use super::super::mvc_lanes::{LaneMath, PlainMath};
    use super::*;

    fn ln_lanes(num: [f64; 8], den: [f64; 8]) -> [f64; 8] {
        ln_of_quotient::<PlainMath>(V8(num), V8(den)).0
    }

    #[test]
    fn ln_of_quotient_matches_libm() {
        check_ln_of_quotient(ln_lanes);
    }

    /// The fused arithmetic and AVX-512's refined reciprocal (where the CPU has it) keep the
    /// same error bound.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn ln_of_quotient_matches_libm_with_every_lane_arithmetic() {
        use super::super::mvc_lanes::{Avx512Math, FusedMath};
        check_ln_of_quotient(|num, den| ln_of_quotient::<FusedMath>(V8(num), V8(den)).0);
        if crate::simd_dispatch::cpu().avx512f() {
            check_ln_of_quotient(|num, den| ln_of_quotient::<Avx512Math>(V8(num), V8(den)).0);
        }
    }

    fn check_ln_of_quotient(ln_lanes: impl Fn([f64; 8], [f64; 8]) -> [f64; 8]) {
        let mut worst = 0.0f64;
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..50_000 {
            // Quotients from 1e-30 to 1e30, and near 1 (where ln is small and s carries it).
            let num: [f64; 8] = std::array::from_fn(|_| 10f64.powf(30.0 * (next() - 0.5)));
            let den: [f64; 8] = std::array::from_fn(|l| {
                if l % 2 == 0 {
                    num[l] * (1.0 + 1e-3 * (next() - 0.5))
                } else {
                    10f64.powf(30.0 * (next() - 0.5))
                }
            });
            let got = ln_lanes(num, den);
            for l in 0..8 {
                let exact = (num[l] / den[l]).ln();
                // The reference itself rounds num/den: allow its ulp too.
                let err = (got[l] - exact).abs() / (exact.abs() + 1e-300);
                let reference_rounding = f64::EPSILON / (exact.abs() + 1e-300);
                worst = worst.max(err / (4.0 * f64::EPSILON + reference_rounding));
            }
        }
        assert!(worst <= 1.0, "worst error {worst} of the allowed");
        // Exact cases and a quotient beyond the f64 range.
        assert_eq!(ln_lanes([3.0; 8], [3.0; 8]), [0.0; 8]);
        let big = ln_lanes([1e300; 8], [1e-300; 8])[0];
        assert!((big - 600.0 * 10f64.ln()).abs() < 1e-12, "{big}");
        assert!((ln_lanes([2.0; 8], [1.0; 8])[0] - std::f64::consts::LN_2).abs() < 2e-16);
    }

    /// Every tier splits a positive normal number into the same significand in [1, 2) and
    /// exponent, exactly (AVX-512's `vgetmantpd` / `vgetexppd` against the bit operations).
    #[test]
    fn significand_and_exponent_are_exact_on_every_tier() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut values = vec![
            f64::MIN_POSITIVE,
            f64::MAX,
            1.0,
            2.0,
            0.5,
            1.5,
            std::f64::consts::SQRT_2,
            1.0 - f64::EPSILON / 2.0,
            3.0e-300,
            7.0e250,
        ];
        for _ in 0..4000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            // Random bits with the sign cleared and a normal exponent.
            let exponent = 1 + (state >> 52) % 2046;
            values.push(f64::from_bits((exponent << 52) | (state & ((1 << 52) - 1))));
        }
        for chunk in values.chunks_exact(8) {
            let x = V8(std::array::from_fn(|l| chunk[l]));
            let (significand, exponent) = PlainMath::significand_and_exponent(x);
            for l in 0..8 {
                let (m, e) = (significand.0[l], exponent.0[l]);
                assert!(
                    (1.0..2.0).contains(&m) && e == e.round(),
                    "{} -> {m}, {e}",
                    x.0[l]
                );
                assert_eq!(m * 2f64.powi(e as i32), x.0[l]);
            }
            #[cfg(target_arch = "x86_64")]
            if crate::simd_dispatch::cpu().avx512f() {
                let tier = avx512_significand_and_exponent(x);
                assert_eq!(tier, (significand, exponent), "{x:?}");
            }
        }
    }

    /// AVX-512's split of `x`, called from a function compiled for it.
    #[cfg(target_arch = "x86_64")]
    fn avx512_significand_and_exponent(x: V8) -> (V8, V8) {
        #[target_feature(enable = "avx512f")]
        fn split(x: V8) -> (V8, V8) {
            super::super::mvc_lanes::Avx512Math::significand_and_exponent(x)
        }
        // SAFETY: only called after `avx512f` was detected.
        unsafe { split(x) }
    }

    #[test]
    fn angle_fraction_is_atan2_at_any_scale() {
        let mut worst = 0.0f64;
        for i in 0..20_000 {
            let theta = std::f64::consts::PI * (i as f64 + 0.5) / 20_000.0;
            for scale in [1e-12, 1e-3, 1.0, 4.0, 30.0] {
                let (s, c) = (theta.sin() * scale, theta.cos() * scale);
                let (num, den) = angle_fraction::<PlainMath>(V8::splat(s), V8::splat(c));
                let got = num.0[0] / den.0[0];
                worst = worst.max((got - s.atan2(c)).abs() / s.atan2(c));
            }
        }
        assert!(worst < 1e-15, "worst relative error {worst:e}");
    }
}
