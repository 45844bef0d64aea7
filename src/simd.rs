//! Hot kernels compiled twice, for AVX2 and for baseline x86-64 (SSE2), with the copy
//! chosen at run time. FMA stays off in both, so the copies give the same bits; the tests
//! that compare them are beside each kernel.

/// Whether the processor has AVX2 (the standard library detects it once and caches it).
#[inline(always)]
pub(crate) fn has_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    return std::arch::is_x86_feature_detected!("avx2");
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// Calls a kernel compiled for AVX2 where the processor has it, else its portable copy.
///
/// - `dispatch!(kernel(name: Type = value, …) -> Ret)`: one `#[inline(always)]` kernel,
///   compiled a second time inside a `#[target_feature(enable = "avx2")]` function (`=
///   value` where the argument is not the variable `name`; no `Self` in types or path).
/// - `dispatch!(avx2 = twin, portable = kernel; arg, …)`: two functions of the same
///   arguments, `twin` written for AVX2 (declared on x86-64 only).
macro_rules! dispatch {
    ($($kernel:ident)::+ ($($arg:ident : $ty:ty $(= $value:expr)?),* $(,)?) $(-> $ret:ty)?) => {{
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        fn avx2_copy($($arg: $ty),*) $(-> $ret)? {
            $($kernel)::+($($arg),*)
        }
        $($crate::simd::bind!($arg $(= $value)?);)*
        $crate::simd::dispatch!(avx2 = avx2_copy, portable = $($kernel)::+; $($arg),*)
    }};
    (avx2 = $($twin:ident)::+, portable = $($kernel:ident)::+; $($arg:ident),* $(,)?) => {{
        #[cfg(target_arch = "x86_64")]
        let result = if $crate::simd::has_avx2() {
            // SAFETY: the processor has AVX2.
            unsafe { $($twin)::+($($arg),*) }
        } else {
            $($kernel)::+($($arg),*)
        };
        #[cfg(not(target_arch = "x86_64"))]
        let result = $($kernel)::+($($arg),*);
        result
    }};
}

/// An argument of [`dispatch!`] given a value: a variable of its name (else the variable
/// is already there).
macro_rules! bind {
    ($arg:ident = $value:expr) => {
        let $arg = $value;
    };
    ($arg:ident) => {};
}

pub(crate) use {bind, dispatch};
