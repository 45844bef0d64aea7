//! The FMU binary exports the FMI 2.0 co-simulation functions and nothing else. rustc
//! exports every `#[no_mangle]` function of every crate linked in (fmi-sys's
//! `callback_log` too) through an export list of its own, in which a symbol named as
//! exported outranks a wildcard `local: *`. So the list passed here names the standard's
//! functions as exported (the link fails if one is missing: rustc passes
//! `--no-undefined-version`) and the dependencies' exports as local by name; a test holds
//! the binary's dynamic symbols to exactly the standard's list.

use std::path::PathBuf;

/// The functions of the FMI 2.0 standard's common and co-simulation interfaces, as
/// `fmi2Functions.h` declares them; the FMU exports each one (those it does not support
/// return `fmi2Error` with a message).
const FMI2_FUNCTIONS: [&str; 34] = [
    // Common functions.
    "fmi2GetTypesPlatform",
    "fmi2GetVersion",
    "fmi2SetDebugLogging",
    "fmi2Instantiate",
    "fmi2FreeInstance",
    "fmi2SetupExperiment",
    "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode",
    "fmi2Terminate",
    "fmi2Reset",
    "fmi2GetReal",
    "fmi2GetInteger",
    "fmi2GetBoolean",
    "fmi2GetString",
    "fmi2SetReal",
    "fmi2SetInteger",
    "fmi2SetBoolean",
    "fmi2SetString",
    "fmi2GetFMUstate",
    "fmi2SetFMUstate",
    "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize",
    "fmi2SerializeFMUstate",
    "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative",
    // Co-simulation functions.
    "fmi2SetRealInputDerivatives",
    "fmi2GetRealOutputDerivatives",
    "fmi2DoStep",
    "fmi2CancelStep",
    "fmi2GetStatus",
    "fmi2GetRealStatus",
    "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus",
    "fmi2GetStringStatus",
];

/// `#[no_mangle]` functions of dependencies, kept out of the FMU's exports.
const DEPENDENCY_EXPORTS: [&str; 1] = [
    // fmi-sys's bridge for importers written in Rust, not part of any FMU.
    "callback_log",
];

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    match os.as_str() {
        // ELF: a version script, which lld (cargo's builds) and zig's linker (the portable
        // binary of fmu/build-binary.sh) both accept.
        "linux" | "android" | "freebsd" | "netbsd" | "openbsd" => {
            let lines = |names: &[&str]| -> String {
                names.iter().map(|f| format!("    {f};\n")).collect()
            };
            let script = format!(
                "{{\n  global:\n{}  local:\n{}    *;\n}};\n",
                lines(&FMI2_FUNCTIONS),
                lines(&DEPENDENCY_EXPORTS)
            );
            let path = out.join("fmi2-exports.map");
            std::fs::write(&path, script).expect("write the version script");
            println!(
                "cargo:rustc-cdylib-link-arg=-Wl,--version-script={}",
                path.display()
            );
        }
        // PE: a module-definition file naming the exports, which MinGW's linker takes as
        // an input file (after rustc's own list).
        "windows" => {
            let def: String = FMI2_FUNCTIONS
                .iter()
                .map(|f| format!("    {f}\n"))
                .collect();
            let path = out.join("fmi2-exports.def");
            std::fs::write(&path, format!("EXPORTS\n{def}")).expect("write the .def file");
            println!("cargo:rustc-cdylib-link-arg=-Wl,{}", path.display());
        }
        // Mach-O: the exported symbols, each with the leading underscore of C names (for
        // ld64 or ld64.lld, which fmu/ld64.sh runs: zig's linker has no export list), no
        // dylib that nothing uses (libc's iconv functions name libiconv).
        "macos" => {
            println!("cargo:rustc-cdylib-link-arg=-Wl,-dead_strip_dylibs");
            // The library's own name, in place of the path it was linked at.
            println!(
                "cargo:rustc-cdylib-link-arg=-Wl,-install_name,@rpath/libtensegrity_fmu_binary.dylib"
            );
            let list: String = FMI2_FUNCTIONS.iter().map(|f| format!("_{f}\n")).collect();
            let path = out.join("fmi2-exports.txt");
            std::fs::write(&path, list).expect("write the exported symbols list");
            println!(
                "cargo:rustc-cdylib-link-arg=-Wl,-exported_symbols_list,{}",
                path.display()
            );
        }
        _ => {}
    }
}
