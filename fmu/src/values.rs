//! `fmi2Get*` / `fmi2Set*`: each converts its arrays (checked against `nvr` before any
//! element is read) and calls the instance once; Booleans and Integers pass through as
//! doubles without a per-call allocation.

use fmi_sys::fmi2::*;
use tensegrity_fmu::fmi::variables::BaseType;

use crate::call;
use crate::ffi::{slice, slice_mut, value_references};

#[no_mangle]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    call(c, "fmi2GetReal", |i| {
        let vrs = value_references(i, vr, nvr, "fmi2GetReal")?;
        let values = slice_mut(value, nvr, "fmi2GetReal: value")?;
        i.get("fmi2GetReal", BaseType::Real, vrs, values)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    call(c, "fmi2GetBoolean", |i| {
        let vrs = value_references(i, vr, nvr, "fmi2GetBoolean")?;
        let out = slice_mut(value, nvr, "fmi2GetBoolean: value")?;
        i.get_each("fmi2GetBoolean", BaseType::Boolean, vrs, |k, v| {
            out[k] = fmi2Boolean::from(v != 0.0)
        })
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    call(c, "fmi2GetInteger", |i| {
        let vrs = value_references(i, vr, nvr, "fmi2GetInteger")?;
        let out = slice_mut(value, nvr, "fmi2GetInteger: value")?;
        i.get_each("fmi2GetInteger", BaseType::Integer, vrs, |k, v| {
            out[k] = v as fmi2Integer
        })
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *mut fmi2String,
) -> fmi2Status {
    call(c, "fmi2GetString", |i| {
        let vrs = value_references(i, vr, nvr, "fmi2GetString")?;
        i.untyped("fmi2GetString", vrs)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    call(c, "fmi2SetReal", |i| {
        let vrs = value_references(i, vr, nvr, "fmi2SetReal")?;
        let values = slice(value, nvr, "fmi2SetReal: value")?;
        i.set("fmi2SetReal", BaseType::Real, vrs, values)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    call(c, "fmi2SetBoolean", |i| {
        let vrs = value_references(i, vr, nvr, "fmi2SetBoolean")?;
        let values = slice(value, nvr, "fmi2SetBoolean: value")?;
        i.set_each("fmi2SetBoolean", BaseType::Boolean, vrs, |k| {
            f64::from(u8::from(values[k] != 0))
        })
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    call(c, "fmi2SetInteger", |i| {
        let vrs = value_references(i, vr, nvr, "fmi2SetInteger")?;
        let values = slice(value, nvr, "fmi2SetInteger: value")?;
        i.set_each("fmi2SetInteger", BaseType::Integer, vrs, |k| {
            f64::from(values[k])
        })
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *const fmi2String,
) -> fmi2Status {
    call(c, "fmi2SetString", |i| {
        let vrs = value_references(i, vr, nvr, "fmi2SetString")?;
        i.untyped("fmi2SetString", vrs)
    })
}
