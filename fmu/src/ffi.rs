//! Pointer-to-slice conversion and the logger bridge: the only `unsafe` helpers.

use std::ffi::{CStr, CString};
use std::fmt::Display;

use fmi_sys::fmi2::*;
use tensegrity_fmu::fmi::{Category, FmiError, Instance};

/// An instance plus what the importer gave for logging.
pub struct Component {
    pub instance: Instance,
    logger: fmi2CallbackLogger,
    environment: fmi2ComponentEnvironment,
}

impl Component {
    pub fn new(instance: Instance, functions: &fmi2CallbackFunctions) -> Self {
        Self {
            instance,
            logger: functions.logger,
            environment: functions.componentEnvironment,
        }
    }

    /// Sends the instance's queued messages to the importer's logger.
    pub fn flush_log(&mut self) {
        // Most calls log nothing: they must not pay for the copy of the name.
        if !self.instance.has_messages() {
            return;
        }
        let name = self.instance.name().to_string();
        for m in self.instance.drain_messages() {
            let status = match m.category {
                Category::Events => fmi2Status_fmi2OK,
                Category::Warning => fmi2Status_fmi2Warning,
                Category::Error => fmi2Status_fmi2Error,
            };
            send(
                self.logger,
                self.environment,
                &name,
                status,
                m.category,
                &m.text,
            );
        }
    }
}

/// Logs through the callbacks of `fmi2Instantiate`.
pub fn log(
    functions: &fmi2CallbackFunctions,
    name: &str,
    status: fmi2Status,
    category: Category,
    text: &str,
) {
    send(
        functions.logger,
        functions.componentEnvironment,
        name,
        status,
        category,
        text,
    );
}

fn send(
    logger: fmi2CallbackLogger,
    environment: fmi2ComponentEnvironment,
    name: &str,
    status: fmi2Status,
    category: Category,
    text: &str,
) {
    let Some(logger) = logger else { return };
    // The logger is printf-like: a literal % must be doubled.
    let message = cstring(&text.replace('%', "%%"));
    let name = cstring(name);
    let category = cstring(category.name());
    unsafe {
        logger(
            environment,
            name.as_ptr(),
            status,
            category.as_ptr(),
            message.as_ptr(),
        )
    };
}

fn cstring(s: &str) -> CString {
    CString::new(s.replace('\0', " ")).unwrap_or_default()
}

/// A C string argument, if not NULL.
pub unsafe fn text(p: fmi2String) -> Option<String> {
    (!p.is_null()).then(|| CStr::from_ptr(p).to_string_lossy().into_owned())
}

/// Refuses NULL for `n > 0`, and a count no array of `T` can have (it would abort the
/// host, or be undefined behaviour, to treat it as one).
fn check<T>(p: *const T, n: usize, what: impl Display) -> Result<(), FmiError> {
    if n > 0 && p.is_null() {
        return Err(FmiError::refused(format!(
            "{what} is NULL but {n} elements were passed"
        )));
    }
    let limit = isize::MAX as usize / std::mem::size_of::<T>().max(1);
    if n > limit {
        return Err(FmiError::refused(format!(
            "{what}: {n} elements is more than any array can hold; pass the number of elements"
        )));
    }
    Ok(())
}

/// `n` elements at `p`; NULL is allowed only for `n == 0`.
pub unsafe fn slice<'a, T>(p: *const T, n: usize, what: impl Display) -> Result<&'a [T], FmiError> {
    check(p, n, what)?;
    Ok(if n == 0 {
        &[]
    } else {
        std::slice::from_raw_parts(p, n)
    })
}

/// `n` writable elements at `p`; NULL is allowed only for `n == 0`.
pub unsafe fn slice_mut<'a, T>(
    p: *mut T,
    n: usize,
    what: impl Display,
) -> Result<&'a mut [T], FmiError> {
    check(p, n, what)?;
    Ok(if n == 0 {
        &mut []
    } else {
        std::slice::from_raw_parts_mut(p, n)
    })
}

/// Value references of a get/set call: at most [`MAX_REQUESTS_PER_VARIABLE`] per variable
/// of the FMU (plus a margin), so a wrong `nvr` is refused before any element is read.
pub unsafe fn value_references<'a>(
    instance: &Instance,
    vr: *const fmi2ValueReference,
    nvr: usize,
    call: &str,
) -> Result<&'a [fmi2ValueReference], FmiError> {
    let limit = MAX_REQUESTS_PER_VARIABLE * instance.table().variables.len() + 1024;
    if nvr > limit {
        return Err(FmiError::refused(format!(
            "{call}: nvr = {nvr} value references, more than {limit} ({MAX_REQUESTS_PER_VARIABLE} \
             per variable of this FMU); pass the number of elements of vr"
        )));
    }
    // The label is formatted only into an error: a good call allocates nothing.
    slice(vr, nvr, format_args!("{call}: vr"))
}

/// Repeats of a variable in one call beyond which `nvr` is taken for a mistake.
pub const MAX_REQUESTS_PER_VARIABLE: usize = 16;
