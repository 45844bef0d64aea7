//! The generic FMI 2.0 co-simulation binary. Every function is thin: null checks, a
//! panic guard, argument conversion, one call to a safe `Instance` method, and the status
//! mapping; messages go to the importer's logger. One binary serves every scene: the
//! model is read from `resources/` at `fmi2Instantiate`.
#![allow(non_snake_case)]
#![allow(clippy::missing_safety_doc)]

#[cfg(test)]
mod allocation_tests;
mod ffi;
mod guard;
mod state;
mod values;

use std::ffi::c_char;
use std::panic::AssertUnwindSafe;
use std::ptr;

use fmi_sys::fmi2::*;
use tensegrity_fmu::fmi::{resource_path, Category, FmiError, FmiResult, Instance, Status};

use ffi::{slice, text, Component};
pub use state::*;
pub use values::*;

const ERROR: fmi2Status = fmi2Status_fmi2Error;

/// Most category names one `fmi2SetDebugLogging` may list (each may repeat a few times).
const MAX_CATEGORIES: usize = 64;

fn status(s: Status) -> fmi2Status {
    match s {
        Status::Ok => fmi2Status_fmi2OK,
        Status::Warning => fmi2Status_fmi2Warning,
        Status::Discard => fmi2Status_fmi2Discard,
        Status::Error => fmi2Status_fmi2Error,
    }
}

/// Runs `body` on the instance behind `c`, catching panics and logging failures. The
/// logging itself runs inside the guard too, so nothing can unwind into the host.
fn call(c: fmi2Component, name: &str, body: impl FnOnce(&mut Instance) -> FmiResult) -> fmi2Status {
    let Some(component) = (unsafe { (c as *mut Component).as_mut() }) else {
        return ERROR;
    };
    let result = guard::quietly(AssertUnwindSafe(|| body(&mut component.instance)));
    guard::quietly(AssertUnwindSafe(|| {
        let out = match result {
            Ok(Ok(s)) => status(s),
            Ok(Err(e)) => {
                component.instance.fail(&e);
                status(e.status)
            }
            Err(panic) => {
                component.instance.fail(&FmiError::failed(format!(
                    "{name}: internal error: {panic}"
                )));
                ERROR
            }
        };
        component.flush_log();
        out
    }))
    .unwrap_or(ERROR)
}

fn fail(message: String) -> FmiError {
    FmiError::refused(message)
}

#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    fmi2TypesPlatform.as_ptr().cast()
}

#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    fmi2Version.as_ptr().cast()
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    loggingOn: fmi2Boolean,
    nCategories: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    call(c, "fmi2SetDebugLogging", |i| {
        if nCategories > MAX_CATEGORIES {
            return Err(fail(format!(
                "fmi2SetDebugLogging: nCategories = {nCategories}, but this FMU has {} log \
                 categories; pass the number of elements of categories (0 for all)",
                Category::ALL.len()
            )));
        }
        let names = slice(categories, nCategories, "fmi2SetDebugLogging: categories")?;
        let names: Vec<String> = names.iter().map(|&p| text(p).unwrap_or_default()).collect();
        i.set_debug_logging(loggingOn != 0, &names)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    instanceName: fmi2String,
    fmuType: fmi2Type,
    fmuGUID: fmi2String,
    fmuResourceLocation: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    loggingOn: fmi2Boolean,
) -> fmi2Component {
    let Some(functions) = functions.as_ref() else {
        return ptr::null_mut();
    };
    if functions.logger.is_none() {
        return ptr::null_mut();
    }
    // Everything past the checks above runs inside the guard, logging included.
    guard::quietly(AssertUnwindSafe(|| {
        let name = text(instanceName).unwrap_or_default();
        let report = |message: &str| {
            ffi::log(
                functions,
                &name,
                fmi2Status_fmi2Error,
                Category::Error,
                message,
            )
        };
        let built = guard::quietly(|| {
            if fmuType != fmi2Type_fmi2CoSimulation {
                return Err("fmi2Instantiate: this FMU supports co-simulation only".to_string());
            }
            let guid = text(fmuGUID).ok_or("fmi2Instantiate: fmuGUID is missing")?;
            let location = text(fmuResourceLocation)
                .ok_or("fmi2Instantiate: fmuResourceLocation is missing")?;
            let resources =
                resource_path(&location).map_err(|e| format!("fmi2Instantiate: {e}"))?;
            Instance::instantiate(&name, &guid, &resources, loggingOn != 0)
        });
        match built {
            Ok(Ok(instance)) => {
                let mut component = Box::new(Component::new(instance, functions));
                component.flush_log();
                Box::into_raw(component) as fmi2Component
            }
            Ok(Err(message)) => {
                report(&message);
                ptr::null_mut()
            }
            Err(panic) => {
                report(&format!("fmi2Instantiate: internal error: {panic}"));
                ptr::null_mut()
            }
        }
    }))
    .unwrap_or(ptr::null_mut())
}

#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    if !c.is_null() {
        let _ = guard::quietly(AssertUnwindSafe(|| {
            drop(Box::from_raw(c as *mut Component))
        }));
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    _toleranceDefined: fmi2Boolean,
    _tolerance: fmi2Real,
    startTime: fmi2Real,
    stopTimeDefined: fmi2Boolean,
    stopTime: fmi2Real,
) -> fmi2Status {
    call(c, "fmi2SetupExperiment", |i| {
        i.setup_experiment(startTime, (stopTimeDefined != 0).then_some(stopTime))
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    call(
        c,
        "fmi2EnterInitializationMode",
        Instance::enter_initialization_mode,
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    call(
        c,
        "fmi2ExitInitializationMode",
        Instance::exit_initialization_mode,
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    call(c, "fmi2Terminate", Instance::terminate)
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    call(c, "fmi2Reset", Instance::reset)
}

/// The functions this FMU declares it does not provide: logged errors.
fn unsupported(c: fmi2Component, name: &str, why: &str) -> fmi2Status {
    call(c, name, |_| Err(fail(format!("{name}: {why}"))))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    _vUnknown_ref: *const fmi2ValueReference,
    _nUnknown: usize,
    _vKnown_ref: *const fmi2ValueReference,
    _nKnown: usize,
    _dvKnown: *const fmi2Real,
    _dvUnknown: *mut fmi2Real,
) -> fmi2Status {
    unsupported(
        c,
        "fmi2GetDirectionalDerivative",
        "not supported (providesDirectionalDerivative=false); difference the outputs of two \
         runs, or take the linear model from the CLI's `linearize` command",
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *const fmi2Real,
) -> fmi2Status {
    unsupported(
        c,
        "fmi2SetRealInputDerivatives",
        "not supported: inputs are held constant over a step (canInterpolateInputs=false); \
         set the input values with fmi2SetReal before each fmi2DoStep",
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *mut fmi2Real,
) -> fmi2Status {
    unsupported(
        c,
        "fmi2GetRealOutputDerivatives",
        "not supported (maxOutputDerivativeOrder=0); read the outputs with fmi2GetReal at \
         each communication point (node velocities are outputs too)",
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2DoStep(
    c: fmi2Component,
    currentCommunicationPoint: fmi2Real,
    communicationStepSize: fmi2Real,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
) -> fmi2Status {
    call(c, "fmi2DoStep", |i| {
        i.do_step(currentCommunicationPoint, communicationStepSize)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    unsupported(
        c,
        "fmi2CancelStep",
        "not supported: fmi2DoStep always completes before it returns \
         (canRunAsynchronuously=false), so there is no step to cancel; use fmi2SetFMUstate \
         or fmi2Reset to go back",
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetStatus(
    c: fmi2Component,
    _s: fmi2StatusKind,
    _value: *mut fmi2Status,
) -> fmi2Status {
    unsupported(
        c,
        "fmi2GetStatus",
        "not supported: fmi2DoStep always completes before it returns, so no status is \
         pending; its return value is the status",
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Real,
) -> fmi2Status {
    call(c, "fmi2GetRealStatus", |i| {
        if s != fmi2StatusKind_fmi2LastSuccessfulTime {
            return Err(fail(
                "fmi2GetRealStatus: only fmi2LastSuccessfulTime is available".into(),
            ));
        }
        let out = value
            .as_mut()
            .ok_or_else(|| fail("fmi2GetRealStatus: value is NULL".into()))?;
        *out = i.last_successful_time()?;
        Ok(Status::Ok)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: fmi2Component,
    _s: fmi2StatusKind,
    _value: *mut fmi2Integer,
) -> fmi2Status {
    unsupported(
        c,
        "fmi2GetIntegerStatus",
        "not supported: FMI 2.0 defines no Integer status; use fmi2GetRealStatus or \
         fmi2GetBooleanStatus",
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    call(c, "fmi2GetBooleanStatus", |i| {
        if s != fmi2StatusKind_fmi2Terminated {
            return Err(fail(
                "fmi2GetBooleanStatus: only fmi2Terminated is available".into(),
            ));
        }
        let out = value
            .as_mut()
            .ok_or_else(|| fail("fmi2GetBooleanStatus: value is NULL".into()))?;
        *out = fmi2Boolean::from(i.terminated()?);
        Ok(Status::Ok)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: fmi2Component,
    _s: fmi2StatusKind,
    _value: *mut fmi2String,
) -> fmi2Status {
    unsupported(
        c,
        "fmi2GetStringStatus",
        "not supported: fmi2DoStep always completes before it returns, so no status is \
         pending; its return value is the status",
    )
}

// Each exported signature is checked against the official headers at compile time.
const _: fmi2GetTypesPlatformTYPE = Some(fmi2GetTypesPlatform);
const _: fmi2GetVersionTYPE = Some(fmi2GetVersion);
const _: fmi2SetDebugLoggingTYPE = Some(fmi2SetDebugLogging);
const _: fmi2InstantiateTYPE = Some(fmi2Instantiate);
const _: fmi2FreeInstanceTYPE = Some(fmi2FreeInstance);
const _: fmi2SetupExperimentTYPE = Some(fmi2SetupExperiment);
const _: fmi2EnterInitializationModeTYPE = Some(fmi2EnterInitializationMode);
const _: fmi2ExitInitializationModeTYPE = Some(fmi2ExitInitializationMode);
const _: fmi2TerminateTYPE = Some(fmi2Terminate);
const _: fmi2ResetTYPE = Some(fmi2Reset);
const _: fmi2GetRealTYPE = Some(fmi2GetReal);
const _: fmi2GetIntegerTYPE = Some(fmi2GetInteger);
const _: fmi2GetBooleanTYPE = Some(fmi2GetBoolean);
const _: fmi2GetStringTYPE = Some(fmi2GetString);
const _: fmi2SetRealTYPE = Some(fmi2SetReal);
const _: fmi2SetIntegerTYPE = Some(fmi2SetInteger);
const _: fmi2SetBooleanTYPE = Some(fmi2SetBoolean);
const _: fmi2SetStringTYPE = Some(fmi2SetString);
const _: fmi2GetFMUstateTYPE = Some(fmi2GetFMUstate);
const _: fmi2SetFMUstateTYPE = Some(fmi2SetFMUstate);
const _: fmi2FreeFMUstateTYPE = Some(fmi2FreeFMUstate);
const _: fmi2SerializedFMUstateSizeTYPE = Some(fmi2SerializedFMUstateSize);
const _: fmi2SerializeFMUstateTYPE = Some(fmi2SerializeFMUstate);
const _: fmi2DeSerializeFMUstateTYPE = Some(fmi2DeSerializeFMUstate);
const _: fmi2GetDirectionalDerivativeTYPE = Some(fmi2GetDirectionalDerivative);
const _: fmi2SetRealInputDerivativesTYPE = Some(fmi2SetRealInputDerivatives);
const _: fmi2GetRealOutputDerivativesTYPE = Some(fmi2GetRealOutputDerivatives);
const _: fmi2DoStepTYPE = Some(fmi2DoStep);
const _: fmi2CancelStepTYPE = Some(fmi2CancelStep);
const _: fmi2GetStatusTYPE = Some(fmi2GetStatus);
const _: fmi2GetRealStatusTYPE = Some(fmi2GetRealStatus);
const _: fmi2GetIntegerStatusTYPE = Some(fmi2GetIntegerStatus);
const _: fmi2GetBooleanStatusTYPE = Some(fmi2GetBooleanStatus);
const _: fmi2GetStringStatusTYPE = Some(fmi2GetStringStatus);
