//! FMU state: get, set, free, and the serialized form. Snapshots are boxed Rust values
//! handed to the importer as opaque pointers.

use std::ptr;

use fmi_sys::fmi2::*;
use tensegrity_fmu::fmi::snapshot::Snapshot;
use tensegrity_fmu::fmi::Status;

use crate::ffi::{slice, slice_mut};
use crate::{call, fail};

#[no_mangle]
pub unsafe extern "C" fn fmi2GetFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    call(c, "fmi2GetFMUstate", |i| {
        let slot = state
            .as_mut()
            .ok_or_else(|| fail("fmi2GetFMUstate: FMUstate is NULL".into()))?;
        let snapshot = i.get_state()?;
        match (*slot as *mut Snapshot).as_mut() {
            Some(existing) => *existing = snapshot,
            None => *slot = Box::into_raw(Box::new(snapshot)) as fmi2FMUstate,
        }
        Ok(Status::Ok)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status {
    call(c, "fmi2SetFMUstate", |i| {
        let snapshot = (state as *const Snapshot)
            .as_ref()
            .ok_or_else(|| fail("fmi2SetFMUstate: FMUstate is NULL".into()))?;
        i.set_state(snapshot)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: fmi2Component,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    call(c, "fmi2FreeFMUstate", |_| {
        if let Some(slot) = state.as_mut() {
            if !slot.is_null() {
                drop(Box::from_raw(*slot as *mut Snapshot));
                *slot = ptr::null_mut();
            }
        }
        Ok(Status::Ok)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    state: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    call(c, "fmi2SerializedFMUstateSize", |_| {
        let snapshot = (state as *const Snapshot)
            .as_ref()
            .ok_or_else(|| fail("fmi2SerializedFMUstateSize: FMUstate is NULL".into()))?;
        let size = size
            .as_mut()
            .ok_or_else(|| fail("fmi2SerializedFMUstateSize: size is NULL".into()))?;
        *size = snapshot.to_bytes().len();
        Ok(Status::Ok)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    state: fmi2FMUstate,
    serializedState: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    call(c, "fmi2SerializeFMUstate", |_| {
        let snapshot = (state as *const Snapshot)
            .as_ref()
            .ok_or_else(|| fail("fmi2SerializeFMUstate: FMUstate is NULL".into()))?;
        let bytes = snapshot.to_bytes();
        if size < bytes.len() {
            return Err(fail(format!(
                "fmi2SerializeFMUstate: buffer of {size} bytes is smaller than the {} needed",
                bytes.len()
            )));
        }
        let out = slice_mut(
            serializedState.cast::<u8>(),
            bytes.len(),
            "fmi2SerializeFMUstate: buffer",
        )?;
        out.copy_from_slice(&bytes);
        Ok(Status::Ok)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    serializedState: *const fmi2Byte,
    size: usize,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    call(c, "fmi2DeSerializeFMUstate", |i| {
        let bytes = slice(
            serializedState.cast::<u8>(),
            size,
            "fmi2DeSerializeFMUstate: buffer",
        )?;
        let slot = state
            .as_mut()
            .ok_or_else(|| fail("fmi2DeSerializeFMUstate: FMUstate is NULL".into()))?;
        let snapshot = i.deserialize_state(bytes)?;
        match (*slot as *mut Snapshot).as_mut() {
            Some(existing) => *existing = snapshot,
            None => *slot = Box::into_raw(Box::new(snapshot)) as fmi2FMUstate,
        }
        Ok(Status::Ok)
    })
}
