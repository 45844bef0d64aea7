//! Hot kernels compiled twice, for AVX2 and for baseline x86-64 (SSE2), with the copy
//! chosen at run time. FMA stays off in both, so the copies give the same bits; the tests
//! that compare them are beside each kernel.

/// The environment variable that picks the kernels: `scalar` forces the portable copies
/// on any processor, `auto` (or unset) takes AVX2 where the processor has it.
pub const SIMD_VAR: &str = "TENSEGRITY_SIMD";

/// Whether [`SIMD_VAR`] forces the portable kernels; an error names a bad value.
pub fn forced_scalar() -> Result<bool, String> {
    match std::env::var(SIMD_VAR) {
        Err(std::env::VarError::NotPresent) => Ok(false),
        Ok(v) if v.is_empty() || v == "auto" => Ok(false),
        Ok(v) if v == "scalar" => Ok(true),
        Ok(v) => Err(format!(
            "{SIMD_VAR}={v} is not a kernel choice: set it to `scalar` or `auto`, or unset it"
        )),
        Err(e) => Err(format!(
            "{SIMD_VAR}: {e}: set it to `scalar` or `auto`, or unset it"
        )),
    }
}

/// The kernels in use, for logs: `avx2`, or `scalar` with the reason.
pub fn kernels() -> &'static str {
    if has_avx2() {
        "avx2"
    } else if forced_scalar().unwrap_or(false) {
        "scalar (TENSEGRITY_SIMD=scalar)"
    } else if cfg!(target_arch = "x86_64") {
        "scalar (the processor has no AVX2)"
    } else {
        "scalar (not x86-64)"
    }
}

/// Whether to run the AVX2 kernels: the processor has AVX2 and [`SIMD_VAR`] does not force
/// the portable ones (read once; a bad value counts as `auto`).
#[inline(always)]
pub(crate) fn has_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        static USE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
        *USE.get_or_init(|| {
            !forced_scalar().unwrap_or(false) && std::arch::is_x86_feature_detected!("avx2")
        })
    }
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
