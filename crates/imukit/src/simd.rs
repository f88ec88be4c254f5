//! Runtime CPU dispatch of the hot kernels: the one owner of which instruction set they run with.
//!
//! One build carries every kernel entry loop three times (twice for a kernel capped at AVX2:
//! [`simd_dispatch!`](crate::simd_dispatch)'s `widest = avx2;`), compiled for
//!
//! | [`Path`] | target features | chosen when |
//! |---|---|---|
//! | `avx512` | AVX-512 F/DQ/BW/VL, AVX2, FMA, BMI1/2 | the CPU has them all |
//! | `avx2` | AVX2, FMA, BMI1/2 | the CPU has them (no AVX-512) |
//! | `baseline` | the build's target (x86-64: SSE2) | otherwise, and on other architectures |
//!
//! and picks one at run time, once per process ([`path`]): the best the CPU has, or the one named
//! by the environment variable `IMUKIT_SIMD` (`baseline`, `avx2`, `avx512`; `auto` or unset: the
//! best), read the first time a kernel runs. A forced path the CPU lacks falls back to the best
//! one it has below it, never to an instruction the CPU cannot run.
//!
//! The paths compute the same operations in the same order (no fast-math: LLVM neither contracts
//! `a·b + c` into an FMA nor reassociates sums), so their results are equal bit for bit, except
//! in kernels that ask for fused multiply-adds: the form `fn name<const FMA: bool>(…)` of the
//! macro compiles its body with `FMA = true` on the AVX paths and `false` on the baseline, and the
//! body passes it on (the preintegration step runs its 3×3 block algebra in 256-bit vectors with
//! fused multiply-adds, `mat3::Lanes`). Those kernels
//! differ between paths by rounding only: each fused `a·b + c` rounds once where the baseline
//! rounds twice, sums in the same order. The tests (`tests/test_simd_paths.py`) hold every path to
//! 1e-12 relative of the baseline (measured for the fused preintegration: ≤ 3e-15 in deltas,
//! covariances and bias Jacobians; a wrong lane or a dropped term would be far above it).
//!
//! A kernel adopts the dispatch by wrapping its entry loop (a free function) in
//! [`simd_dispatch!`](crate::simd_dispatch); everything the loop calls is inlined into each copy
//! when it is `#[inline]` (or small) and defined in this crate. `docs/performance.md` has the how-to.

use std::sync::OnceLock;

use crate::error::{Error, Result};

/// An instruction-set path of the dispatched kernels (module table), in rising order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Path {
    /// The build's own target.
    Baseline,
    /// AVX2 with FMA.
    Avx2,
    /// AVX-512 (F, DQ, BW, VL) with AVX2 and FMA.
    Avx512,
}

crate::named_enum!(Path, "IMUKIT_SIMD", [Baseline => "baseline", Avx2 => "avx2", Avx512 => "avx512"]);

/// The environment variable that forces a path.
pub const VARIABLE: &str = "IMUKIT_SIMD";

/// The paths this CPU can run, best first (`Baseline` always).
pub fn supported() -> Vec<Path> {
    let mut paths = Vec::with_capacity(3);
    #[cfg(target_arch = "x86_64")]
    {
        let avx2 = std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma")
            && std::arch::is_x86_feature_detected!("bmi1")
            && std::arch::is_x86_feature_detected!("bmi2");
        let avx512 = avx2
            && std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512dq")
            && std::arch::is_x86_feature_detected!("avx512bw")
            && std::arch::is_x86_feature_detected!("avx512vl");
        if avx512 {
            paths.push(Path::Avx512);
        }
        if avx2 {
            paths.push(Path::Avx2);
        }
    }
    paths.push(Path::Baseline);
    paths
}

/// The path `IMUKIT_SIMD` asks for: `None` when unset, empty or `auto`; an
/// [`Error::Parameter`] naming the variable for an unknown value.
pub fn requested() -> Result<Option<Path>> {
    match std::env::var(VARIABLE) {
        Err(_) => Ok(None),
        Ok(v) if v.is_empty() || v == "auto" => Ok(None),
        Ok(v) => v.parse::<Path>().map(Some).map_err(|_| Error::Parameter {
            name: VARIABLE,
            expected: "one of 'auto', 'baseline', 'avx2', 'avx512'",
            got: format!("{v:?}"),
        }),
    }
}

/// The path for a request among the supported ones: the request, or the best supported path
/// below it; the best supported without one (an unknown request counts as none: [`requested`]
/// reports it).
fn choose(request: Option<Path>, supported: &[Path]) -> Path {
    let rank = |p: Path| p as u8;
    supported
        .iter()
        .copied()
        .find(|&p| request.is_none_or(|r| rank(p) <= rank(r)))
        .unwrap_or(Path::Baseline)
}

/// The path every dispatched kernel of this process runs (decided on first use). An unknown
/// `IMUKIT_SIMD` counts as unset here (a kernel has no error to return for it); callers that
/// must refuse it check [`requested`] first, as the Python package does at import.
pub fn path() -> Path {
    static PATH: OnceLock<Path> = OnceLock::new();
    *PATH.get_or_init(|| choose(requested().ok().flatten(), &supported()))
}

/// Defines `fn $name(args) -> R { body }` compiled once per [`Path`] and dispatched on [`path`]
/// (the module docs). Free functions with plain `ident: Type` arguments; lifetimes may be named
/// after the name (`fn run<'a>(…)`), or one bounded type parameter (`fn run<L: Law>(…)`), or one
/// `const FMA: bool` (`fn run<const FMA: bool>(…)`: the body sees `true` on the AVX paths, `false`
/// on the baseline, and decides what to fuse), and `impl Trait` argument types are accepted.
///
/// `widest = avx2;` before the function caps it at the AVX2 copy: the `avx512` path runs that one
/// and no AVX-512 copy is compiled. For kernels whose AVX-512 copy measured slower than their AVX2
/// one: a dependent scalar chain that LLVM's vectoriser packs into wider registers through
/// cross-lane shuffles (`vpermt2pd`, `vpermpd`), each a few cycles on the chain
/// (`docs/performance.md`, "The AVX-512 copy where it pays").
///
/// ```
/// imukit::simd_dispatch! {
///     /// Sum of squares.
///     pub fn sum_squares(x: &[f64]) -> f64 {
///         x.iter().map(|v| v * v).sum()
///     }
/// }
/// assert_eq!(sum_squares(&[3.0, 4.0]), 25.0);
///
/// imukit::simd_dispatch! {
///     widest = avx2;
///     /// A running sum, a chain of dependent adds: no AVX-512 copy.
///     pub fn running_sum(x: &mut [f64]) -> () {
///         for k in 1..x.len() {
///             x[k] += x[k - 1];
///         }
///     }
/// }
/// let mut x = [1.0, 2.0, 3.0];
/// running_sum(&mut x);
/// assert_eq!(x, [1.0, 3.0, 6.0]);
/// ```
#[macro_export]
macro_rules! simd_dispatch {
    (
        @emit $widest:ident [$($generics:tt)*] [$($extra:tt)*] [$($fast:tt)*] [$($plain:tt)*]
        $(#[$meta:meta])*
        $vis:vis fn $name:ident ($($arg:ident : $ty:ty),*) -> $ret:ty $body:block
    ) => {
        $(#[$meta])*
        $vis fn $name<$($generics)*>($($arg: $ty),*) -> $ret {
            #[inline(always)]
            fn portable<$($generics)* $($extra)*>($($arg: $ty),*) -> $ret $body
            $crate::simd_dispatch!(@copy $widest [$($generics)*] [$($fast)*] ($($arg: $ty),*) -> $ret);
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2,fma,bmi1,bmi2")]
            fn avx2<$($generics)*>($($arg: $ty),*) -> $ret {
                portable$($fast)*($($arg),*)
            }
            match $crate::simd::path() {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: `path()` is `Avx512` only where the CPU has every feature `avx512` enables,
                // which include every feature `avx2` enables (`supported`).
                #[allow(unsafe_code)]
                $crate::simd::Path::Avx512 => unsafe { $widest($($arg),*) },
                #[cfg(target_arch = "x86_64")]
                // SAFETY: `path()` is `Avx2` only where the CPU has every feature `avx2` enables.
                #[allow(unsafe_code)]
                $crate::simd::Path::Avx2 => unsafe { avx2($($arg),*) },
                _ => portable$($plain)*($($arg),*),
            }
        }
    };
    // The AVX-512 copy, for a kernel not capped at AVX2.
    (@copy avx512 [$($generics:tt)*] [$($fast:tt)*] ($($arg:ident : $ty:ty),*) -> $ret:ty) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f,avx512dq,avx512bw,avx512vl,avx2,fma,bmi1,bmi2")]
        fn avx512<$($generics)*>($($arg: $ty),*) -> $ret {
            portable$($fast)*($($arg),*)
        }
    };
    (@copy avx2 $($unused:tt)*) => {};
    (
        @parse $widest:ident
        $(#[$meta:meta])*
        $vis:vis fn $name:ident <const $fma:ident : bool> ($($arg:ident : $ty:ty),* $(,)?) -> $ret:ty $body:block
    ) => {
        $crate::simd_dispatch!(@emit $widest [] [const $fma: bool] [::<true>] [::<false>] $(#[$meta])* $vis fn $name ($($arg: $ty),*) -> $ret $body);
    };
    (
        @parse $widest:ident
        $(#[$meta:meta])*
        $vis:vis fn $name:ident $(<$($lt:lifetime),+>)? ($($arg:ident : $ty:ty),* $(,)?) -> $ret:ty $body:block
    ) => {
        $crate::simd_dispatch!(@emit $widest [$($($lt),+)?] [] [] [] $(#[$meta])* $vis fn $name ($($arg: $ty),*) -> $ret $body);
    };
    (
        @parse $widest:ident
        $(#[$meta:meta])*
        $vis:vis fn $name:ident <$t:ident : $bound:path> ($($arg:ident : $ty:ty),* $(,)?) -> $ret:ty $body:block
    ) => {
        $crate::simd_dispatch!(@emit $widest [$t: $bound] [] [] [] $(#[$meta])* $vis fn $name ($($arg: $ty),*) -> $ret $body);
    };
    // An internal form no arm above accepts: a signature the macro does not support (two type
    // parameters, no return type, `widest = …` after the doc comment). Without this arm it would
    // reach the one below and recurse until the compiler's limit.
    (@ $($unsupported:tt)*) => {
        compile_error!("simd_dispatch!: unsupported form; see the macro's docs for the accepted signatures");
    };
    (widest = avx2; $($function:tt)*) => {
        $crate::simd_dispatch!(@parse avx2 $($function)*);
    };
    ($($function:tt)*) => {
        $crate::simd_dispatch!(@parse avx512 $($function)*);
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_request_falls_back_to_the_best_supported_path_below_it() {
        let all = [Path::Avx512, Path::Avx2, Path::Baseline];
        let no512 = [Path::Avx2, Path::Baseline];
        assert_eq!(choose(None, &all), Path::Avx512);
        assert_eq!(choose(Some(Path::Avx2), &all), Path::Avx2);
        assert_eq!(choose(Some(Path::Baseline), &all), Path::Baseline);
        assert_eq!(choose(Some(Path::Avx512), &no512), Path::Avx2);
        assert_eq!(choose(None, &[Path::Baseline]), Path::Baseline);
    }

    #[test]
    fn baseline_is_always_supported_and_last() {
        assert_eq!(supported().last(), Some(&Path::Baseline));
    }
}
