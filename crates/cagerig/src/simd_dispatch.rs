//! One kernel body compiled for several instruction sets, picked at run time: the
//! [`simd_dispatch!`] macro and the CPU features it reads ([`cpu`], detected once per process).
//!
//! Most of this crate is compiled for the x86-64 baseline (SSE2). A hot kernel is written once as
//! an `#[inline(always)]` generic body; `simd_dispatch!` writes, from the signature given once,
//! one `#[target_feature]` wrapper per tier (whose only code is a call of the body, so the body is
//! compiled again inside it with the wider registers) and the dispatcher, which calls the first
//! tier the CPU supports and the body itself otherwise:
//!
//! ```ignore
//! simd_dispatch! {
//!     /// `sums[r] += …` (the dispatcher's doc comment).
//!     fn accumulate(items: &[(u64, u32, f64, f64)], tables: &Tables<'_>, sums: &mut [f64])
//!         => accumulate_generic;
//!     avx512f: accumulate_avx512;
//!     avx2: accumulate_avx2;
//! }
//! ```
//!
//! - **Signature:** a free function or a method (`&self` / `&mut self` first); generic type and
//!   const parameters go in square brackets after the name (`fn add_columns[W: Weight, const N:
//!   usize](&mut self, …)`) and are inferred from the arguments in the calls; parameters are plain
//!   names; an optional `-> Return`.
//! - **`=> body`:** the body every tier calls, and the baseline: a path (`Self::add_columns_generic`
//!   for a method, called with `self` first).
//! - **Tiers**, widest first: `avx512f`, `avx2` or `avx2_fma` (AVX2 and FMA), each naming its
//!   wrapper (callable directly where a test compares tiers). A tier may call its own instance of
//!   the body: `avx2_fma: evaluate_rows_avx2 => evaluate_rows_generic::<FusedMath>;`
//!   (`coords/mvc_batch.rs`, where the lane arithmetic is a type parameter).
//!
//! **The same bits on every tier** is the body's to keep, as before: Rust never contracts `a * b +
//! c` into a fused multiply-add (and `mul_add` is correctly rounded with or without FMA), so a
//! body without intrinsics gives the same bits whichever tier runs it (the same-bits tests in
//! `skinning/`, `cage_coords/`, `cor_centres/` and `session/display_path.rs` check it); where a
//! tier's arithmetic differs it says so with a body of its own. The macro only chooses how the
//! body is compiled; it adds no arithmetic.
//!
//! **No closures in the body's hot loops.** A closure (also the one inside `array::from_fn` or
//! an array's `map`) is a function of its own; where LLVM does not inline it into the wrapper,
//! it is compiled without the tier's features, and a `mul_add` in it becomes a libm call per
//! lane. Whether it is inlined depends on the build (the MVC kernel was 3× slower in the CLI
//! than in an example from the same source): write lane loops with `per_lane!`
//! (`coords/mvc_lanes.rs`) and helpers as `#[inline(always)]` functions.
//!
//! The one `unsafe` of every dispatch is in the macro, justified once: a wrapper is called only
//! after [`cpu`] reported its tier's features.

// Elsewhere than on x86-64 every dispatcher calls the body directly and reads no feature.
#![cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]

use std::sync::atomic::{AtomicU8, Ordering};

/// The CPU features the dispatched kernels use ([`cpu`]); one bit each.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Cpu(u8);

const AVX512F: u8 = 1;
const AVX2: u8 = 2;
const FMA: u8 = 4;
/// Set once the features were detected (so 0 means "not yet").
const DETECTED: u8 = 0x80;

/// The detected [`Cpu`] with [`DETECTED`], or 0 before the first [`cpu`].
static FEATURES: AtomicU8 = AtomicU8::new(0);

impl Cpu {
    /// AVX-512 Foundation (the `avx512f` tier).
    #[inline]
    pub(crate) fn avx512f(self) -> bool {
        self.0 & AVX512F != 0
    }

    /// AVX2 (the `avx2` tier).
    #[inline]
    pub(crate) fn avx2(self) -> bool {
        self.0 & AVX2 != 0
    }

    /// AVX2 and FMA (the `avx2_fma` tier).
    #[inline]
    pub(crate) fn avx2_fma(self) -> bool {
        self.0 & (AVX2 | FMA) == AVX2 | FMA
    }
}

/// The CPU's features, detected on the first call and then read from one atomic (a relaxed load:
/// every thread that detects finds the same bits).
#[inline]
pub(crate) fn cpu() -> Cpu {
    let bits = FEATURES.load(Ordering::Relaxed);
    if bits & DETECTED != 0 {
        return Cpu(bits);
    }
    detect()
}

#[cold]
fn detect() -> Cpu {
    #[cfg(not(target_arch = "x86_64"))]
    let bits = DETECTED;
    #[cfg(target_arch = "x86_64")]
    let bits = {
        use std::arch::is_x86_feature_detected;
        let mut bits = DETECTED;
        for (present, bit) in [
            (is_x86_feature_detected!("avx512f"), AVX512F),
            (is_x86_feature_detected!("avx2"), AVX2),
            (is_x86_feature_detected!("fma"), FMA),
        ] {
            if present {
                bits |= bit;
            }
        }
        bits
    };
    FEATURES.store(bits, Ordering::Relaxed);
    Cpu(bits)
}

/// A kernel compiled per instruction-set tier and its run-time dispatcher; see the
/// [module documentation](self) for the grammar.
macro_rules! simd_dispatch {
    // The three receiver forms: `&mut self`, `&self`, none. Each gathers the signature into one
    // group (the wrapper rule expands it once per tier) and passes how the calls start.
    (
        $(#[$attr:meta])*
        $vis:vis fn $name:ident $([$($generics:tt)*])?
            (&mut $this:ident $(, $arg:ident : $ty:ty)* $(,)?) $(-> $ret:ty)?
            => $body:path;
        $($tiers:tt)+
    ) => {
        $crate::simd_dispatch::simd_dispatch!(@emit
            [$(#[$attr])*] [$vis] $name
            [[$($($generics)*)?] [&mut $this,] [$($arg: $ty),*] [$(-> $ret)?] [$this,] [$this.]
                [$($arg),*]]
            $body; $($tiers)+
        );
    };
    (
        $(#[$attr:meta])*
        $vis:vis fn $name:ident $([$($generics:tt)*])?
            (&$this:ident $(, $arg:ident : $ty:ty)* $(,)?) $(-> $ret:ty)?
            => $body:path;
        $($tiers:tt)+
    ) => {
        $crate::simd_dispatch::simd_dispatch!(@emit
            [$(#[$attr])*] [$vis] $name
            [[$($($generics)*)?] [&$this,] [$($arg: $ty),*] [$(-> $ret)?] [$this,] [$this.]
                [$($arg),*]]
            $body; $($tiers)+
        );
    };
    (
        $(#[$attr:meta])*
        $vis:vis fn $name:ident $([$($generics:tt)*])?
            ($($arg:ident : $ty:ty),* $(,)?) $(-> $ret:ty)?
            => $body:path;
        $($tiers:tt)+
    ) => {
        $crate::simd_dispatch::simd_dispatch!(@emit
            [$(#[$attr])*] [$vis] $name
            [[$($($generics)*)?] [] [$($arg: $ty),*] [$(-> $ret)?] [] [] [$($arg),*]]
            $body; $($tiers)+
        );
    };

    // The dispatcher and the wrappers.
    (@emit
        [$($attr:tt)*] [$vis:vis] $name:ident $sig:tt $body:path; $($tier:ident : $wrapper:ident $(=> $tier_body:path)?;)+
    ) => {
        $crate::simd_dispatch::simd_dispatch!(@dispatcher
            [$($attr)*] [$vis] $name $sig $body; $($tier $wrapper)+
        );
        $(
            $crate::simd_dispatch::simd_dispatch!(@wrapper
                $tier $wrapper $sig [$($tier_body)?] $body
            );
        )+
    };

    (@dispatcher
        [$($attr:tt)*] [$vis:vis] $name:ident
        [[$($generics:tt)*] [$($receiver:tt)*] [$($arg:ident: $ty:ty),*] [$($ret:tt)*]
            [$($self_arg:tt)*] $method_call:tt $call_args:tt]
        $body:path; $($tier:ident $wrapper:ident)+
    ) => {
        $($attr)*
        $vis fn $name<$($generics)*>($($receiver)* $($arg: $ty),*) $($ret)* {
            #[cfg(target_arch = "x86_64")]
            {
                let cpu = $crate::simd_dispatch::cpu();
                $(
                    $crate::simd_dispatch::simd_dispatch!(@try
                        cpu $tier $wrapper $method_call $call_args
                    );
                )+
            }
            $body($($self_arg)* $($arg),*)
        }
    };

    // One tier of the dispatcher: its wrapper, if the CPU has the tier's features.
    (@try $cpu:ident $tier:ident $wrapper:ident [$($method_call:tt)*] [$($arg:ident),*]) => {
        if $cpu.$tier() {
            // SAFETY: every wrapper is `#[target_feature(enable = ..)]` with exactly the features
            // of its tier (the `@wrapper` rules), and `Cpu::$tier` is true only when the running
            // CPU has all of them (detected with `is_x86_feature_detected!`). That is the whole
            // contract of calling a `target_feature` function; the arguments are passed on
            // unchanged and the wrapper's body is safe code.
            #[expect(unsafe_code, reason = "the call of a tier's #[target_feature] wrapper")]
            let result = unsafe { $($method_call)* $wrapper($($arg),*) };
            return result;
        }
    };

    // Tier names to the features their wrapper is compiled with.
    (@wrapper avx512f $($rest:tt)*) => {
        $crate::simd_dispatch::simd_dispatch!(@wrapper_with "avx512f" $($rest)*);
    };
    (@wrapper avx2 $($rest:tt)*) => {
        $crate::simd_dispatch::simd_dispatch!(@wrapper_with "avx2" $($rest)*);
    };
    (@wrapper avx2_fma $($rest:tt)*) => {
        $crate::simd_dispatch::simd_dispatch!(@wrapper_with "avx2,fma" $($rest)*);
    };

    // A wrapper calls the tier's own body if it names one, else the shared one.
    (@wrapper_with $features:literal $wrapper:ident $sig:tt
        [$tier_body:path] $body:path
    ) => {
        $crate::simd_dispatch::simd_dispatch!(@wrapper_fn
            $features $wrapper $sig $tier_body
        );
    };
    (@wrapper_with $features:literal $wrapper:ident $sig:tt
        [] $body:path
    ) => {
        $crate::simd_dispatch::simd_dispatch!(@wrapper_fn
            $features $wrapper $sig $body
        );
    };

    (@wrapper_fn $features:literal $wrapper:ident
        [[$($generics:tt)*] [$($receiver:tt)*] [$($arg:ident: $ty:ty),*] [$($ret:tt)*] [$($self_arg:tt)*]
            $method_call:tt $call_args:tt]
        $body:path
    ) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $features)]
        fn $wrapper<$($generics)*>($($receiver)* $($arg: $ty),*) $($ret)* {
            $body($($self_arg)* $($arg),*)
        }
    };
}

pub(crate) use simd_dispatch;

#[cfg(test)]
#[expect(unsafe_code, reason = "the tests call each dispatch wrapper directly")]
mod tests {
    use super::*;

    #[test]
    fn cached_features_match_std_detection() {
        let cpu = cpu();
        assert_eq!(cpu, super::cpu(), "the second call reads the cache");
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected;
            assert_eq!(cpu.avx512f(), is_x86_feature_detected!("avx512f"));
            assert_eq!(cpu.avx2(), is_x86_feature_detected!("avx2"));
            assert_eq!(
                cpu.avx2_fma(),
                is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")
            );
        }
    }

    /// Which instance of a body ran.
    trait Tag {
        const TAG: &'static str;
    }
    struct Plain;
    struct Wide;
    struct Widest;
    impl Tag for Plain {
        const TAG: &'static str = "plain";
    }
    impl Tag for Wide {
        const TAG: &'static str = "wide";
    }
    impl Tag for Widest {
        const TAG: &'static str = "widest";
    }

    #[inline(always)]
    fn tagged_generic<T: Tag>(out: &mut Vec<&'static str>, extra: usize) -> usize {
        out.push(T::TAG);
        extra + 1
    }

    simd_dispatch! {
        /// A free function whose tiers call different instances of the body.
        fn tagged(out: &mut Vec<&'static str>, extra: usize) -> usize
            => tagged_generic::<Plain>;
        avx512f: tagged_avx512 => tagged_generic::<Widest>;
        avx2_fma: tagged_avx2 => tagged_generic::<Wide>;
    }

    /// The tag [`tagged`] should push on this CPU.
    fn expected_tag() -> &'static str {
        #[cfg(target_arch = "x86_64")]
        {
            if cpu().avx512f() {
                return "widest";
            }
            if cpu().avx2_fma() {
                return "wide";
            }
        }
        "plain"
    }

    #[test]
    fn free_function_runs_the_widest_supported_tier() {
        let mut out = Vec::new();
        assert_eq!(tagged(&mut out, 41), 42);
        assert_eq!(out, [expected_tag()]);
    }

    struct Sums<const N: usize>([f64; N]);

    impl<const N: usize> Sums<N> {
        #[inline(always)]
        fn add_generic<W: Into<f64> + Copy, const K: usize>(&mut self, w: [W; K]) {
            for (s, x) in self.0.iter_mut().zip(w) {
                *s += x.into();
            }
        }

        #[inline(always)]
        fn total_generic(&self, scale: f64) -> f64 {
            self.0.iter().sum::<f64>() * scale
        }

        simd_dispatch! {
            /// A `&mut self` method with type and const parameters of its own and of its impl.
            fn add[W: Into<f64> + Copy, const K: usize](&mut self, w: [W; K])
                => Self::add_generic;
            avx512f: add_avx512;
            avx2: add_avx2;
        }

        simd_dispatch! {
            /// A `&self` method with one AVX2 tier.
            fn total(&self, scale: f64,) -> f64 => Self::total_generic;
            avx2: total_avx2;
        }
    }

    #[test]
    fn methods_dispatch_with_generics() {
        let mut sums = Sums([0.0; 3]);
        sums.add([1.0f32, 2.0, 3.0]);
        sums.add([1u8, 1, 1, 1]);
        assert_eq!(sums.0, [2.0, 3.0, 4.0]);
        assert_eq!(sums.total(0.5), 4.5);
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn every_supported_tier_gives_the_baseline_result() {
        let mut plain = Sums([0.25; 4]);
        plain.add_generic([0.1f64, 0.2, 0.3, 0.4]);
        let mut tiers = vec![];
        if cpu().avx512f() {
            let mut s = Sums([0.25; 4]);
            // SAFETY: the CPU has AVX-512F (checked just above).
            unsafe { s.add_avx512([0.1f64, 0.2, 0.3, 0.4]) };
            tiers.push(s.0);
        }
        if cpu().avx2() {
            let mut s = Sums([0.25; 4]);
            // SAFETY: the CPU has AVX2 (checked just above).
            unsafe { s.add_avx2([0.1f64, 0.2, 0.3, 0.4]) };
            tiers.push(s.0);
        }
        for t in tiers {
            assert_eq!(t.map(f64::to_bits), plain.0.map(f64::to_bits));
        }
    }
}
