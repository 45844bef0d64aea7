//! The C ABI allocates nothing per call on the path an importer takes every communication
//! step: `fmi2SetReal` of inputs, `fmi2DoStep`, `fmi2GetReal` of every node position (and
//! of outputs that need an evaluation), with preallocated arrays.

#[path = "../../tests/alloc_support/mod.rs"]
mod alloc_support;

use std::ffi::CString;
use std::ptr;

use fmi_sys::fmi2::*;
use tensegrity_fmu::fmi::guid_for;
use tensegrity_fmu::scene::builtin;

use crate::ffi::Component;
use crate::*;
use alloc_support::{allocations, watch_this_thread};

unsafe extern "C" fn quiet_logger(
    _environment: fmi2ComponentEnvironment,
    _name: fmi2String,
    _status: fmi2Status,
    _category: fmi2String,
    _message: fmi2String,
) {
}

fn callbacks() -> fmi2CallbackFunctions {
    // SAFETY: the System V and Windows x64 conventions pass a variadic call's fixed
    // arguments as a plain call's; this logger reads no variadic argument.
    let logger: unsafe extern "C" fn(
        fmi2ComponentEnvironment,
        fmi2String,
        fmi2Status,
        fmi2String,
        fmi2String,
        ...
    ) = unsafe { std::mem::transmute(quiet_logger as *const ()) };
    fmi2CallbackFunctions {
        logger: Some(logger),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: ptr::null_mut(),
    }
}

/// Set in the child process that runs the test body.
const CHILD: &str = "TENSEGRITY_FFI_ALLOCATION_CHILD";

#[test]
fn a_communication_step_allocates_nothing_through_the_c_abi() {
    // The body runs in a process of its own: its FMI calls install the panic guard's hook,
    // once per process, which the guard's test needs to install after its own host hook.
    if std::env::var_os(CHILD).is_none() {
        let name = "allocation_tests::a_communication_step_allocates_nothing_through_the_c_abi";
        let status = std::process::Command::new(std::env::current_exe().unwrap())
            .args(["--exact", name, "--test-threads", "1"])
            .env(CHILD, "1")
            .status()
            .expect("run the test binary");
        assert!(status.success(), "the test body failed in its own process");
        return;
    }
    let dir = std::env::temp_dir().join(format!("tensegrity-ffi-alloc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = builtin("tower20").unwrap().to_toml_string();
    std::fs::write(dir.join("scene.toml"), &text).unwrap();
    let name = CString::new("alloc").unwrap();
    let guid = CString::new(guid_for(&text)).unwrap();
    let location = CString::new(dir.to_str().unwrap()).unwrap();
    let functions = callbacks();
    unsafe {
        let c = fmi2Instantiate(
            name.as_ptr(),
            fmi2Type_fmi2CoSimulation,
            guid.as_ptr(),
            location.as_ptr(),
            &functions,
            0,
            0,
        );
        assert!(!c.is_null(), "fmi2Instantiate");
        let table = (*(c as *mut Component)).instance.table();
        let vr = |n: &str| table.by_name(n).unwrap().value_reference;
        let positions: Vec<u32> = (0..table.variables.len())
            .filter_map(|k| {
                let n = &table.variables[k].name;
                (n.starts_with("node[")
                    && (n.ends_with(".x") || n.ends_with(".y") || n.ends_with(".z")))
                .then(|| table.variables[k].value_reference)
            })
            .collect();
        let evaluated = [vr("cable[1].tension"), vr("bar[1].force")];
        let force = [table
            .variables
            .iter()
            .find(|v| v.name.ends_with(".fx"))
            .expect("tower20 has force inputs")
            .value_reference];
        assert_eq!(
            fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0),
            fmi2Status_fmi2OK
        );
        assert_eq!(fmi2EnterInitializationMode(c), fmi2Status_fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2Status_fmi2OK);
        let mut values = vec![0.0; positions.len()];
        let mut two = [0.0; 2];
        let h = 1e-3;
        let mut step = |k: usize, with_evaluation: bool| {
            assert_eq!(
                fmi2SetReal(c, force.as_ptr(), 1, [1.0].as_ptr()),
                fmi2Status_fmi2OK
            );
            assert_eq!(fmi2DoStep(c, k as f64 * h, h, 1), fmi2Status_fmi2OK);
            let got = fmi2GetReal(c, positions.as_ptr(), positions.len(), values.as_mut_ptr());
            assert_eq!(got, fmi2Status_fmi2OK);
            if with_evaluation {
                let got = fmi2GetReal(c, evaluated.as_ptr(), 2, two.as_mut_ptr());
                assert_eq!(got, fmi2Status_fmi2OK);
            }
        };
        step(0, true);
        step(1, true);
        watch_this_thread();
        let before = allocations();
        for k in 2..100 {
            step(k, k % 2 == 0);
        }
        let during = allocations() - before;
        assert_eq!(during, 0, "{during} allocations in 98 communication steps");
        assert!(values.iter().all(|v| v.is_finite()) && two[0] > 0.0);
        let _ = fmi2Terminate(c);
        fmi2FreeInstance(c);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
