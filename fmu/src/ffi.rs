//! Pointer-to-slice conversion and the logger bridge: the only `unsafe` helpers.

use std::ffi::{CStr, CString};

use fmi_sys::fmi2::*;
use tensegrity_fmu::fmi::{Category, FmiError, Instance, Status};

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

fn null(what: &str) -> FmiError {
    FmiError {
        status: Status::Error,
        message: format!("{what} is NULL"),
    }
}

/// `n` elements at `p`; NULL is allowed only for `n == 0`.
pub unsafe fn slice<'a, T>(p: *const T, n: usize, what: &str) -> Result<&'a [T], FmiError> {
    match (n, p.is_null()) {
        (0, _) => Ok(&[]),
        (_, true) => Err(null(what)),
        _ => Ok(std::slice::from_raw_parts(p, n)),
    }
}

/// `n` writable elements at `p`; NULL is allowed only for `n == 0`.
pub unsafe fn slice_mut<'a, T>(p: *mut T, n: usize, what: &str) -> Result<&'a mut [T], FmiError> {
    match (n, p.is_null()) {
        (0, _) => Ok(&mut []),
        (_, true) => Err(null(what)),
        _ => Ok(std::slice::from_raw_parts_mut(p, n)),
    }
}
