//! What each platform's binary exports and links, read with LLVM's tools: the 34 FMI 2.0
//! functions and nothing else, only the system's own libraries (no MinGW runtime DLLs on
//! Windows, libSystem alone on macOS), and a universal macOS binary of x86_64 and arm64.
//! The macOS binary cannot run here; these checks are all it gets. Needs
//! `bash fmu/build-binary.sh`.

mod platform_support;

use std::collections::BTreeSet;
use std::process::Command;

use platform_support::{built, stdout};

/// The standard's functions, from the list `fmu/build.rs` exports.
fn fmi2_functions() -> BTreeSet<String> {
    let build = include_str!("../fmu/build.rs");
    let list = &build[build.find("const FMI2_FUNCTIONS").unwrap()..];
    let list = &list[..list.find("];").unwrap()];
    let names: BTreeSet<String> = list
        .split('"')
        .filter(|w| w.starts_with("fmi2"))
        .map(str::to_string)
        .collect();
    assert_eq!(names.len(), 34);
    names
}

/// Lines after `header` in `text` up to the next blank line.
fn section<'a>(text: &'a str, header: &str) -> Vec<&'a str> {
    let start = text
        .find(header)
        .unwrap_or_else(|| panic!("no {header}:\n{text}"));
    text[start..]
        .lines()
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .collect()
}

#[test]
fn the_win64_dll_exports_the_fmi2_functions_and_needs_only_system_dlls() {
    let dll = built("x86_64-pc-windows-gnu", "tensegrity_fmu_binary.dll");
    let text = stdout(Command::new("llvm-objdump").arg("-p").arg(&dll));
    assert!(text.contains("file format coff-x86-64"), "{text}");
    let exports: BTreeSet<String> = section(&text, "Export Table:")
        .iter()
        .skip(3) // DLL name, ordinal base, column titles
        .filter_map(|l| l.split_whitespace().nth(2))
        .map(str::to_string)
        .collect();
    assert_eq!(exports, fmi2_functions());
    let dlls: BTreeSet<String> = text
        .lines()
        .filter_map(|l| l.trim().strip_prefix("DLL Name: "))
        .map(str::to_ascii_lowercase)
        .collect();
    // Windows' own: the kernel, the C runtime (UCRT through its api-ms-win-crt-* forwarders),
    // the random numbers of Rust's std.
    let system = |d: &str| {
        [
            "kernel32.dll",
            "ntdll.dll",
            "bcryptprimitives.dll",
            "ws2_32.dll",
            "userenv.dll",
        ]
        .contains(&d)
            || d.starts_with("api-ms-win-")
    };
    let foreign: Vec<_> = dlls.iter().filter(|d| !system(d)).collect();
    assert!(
        foreign.is_empty(),
        "{foreign:?} (of {dlls:?}) are not part of Windows"
    );
    assert!(dlls.contains("kernel32.dll"), "{dlls:?}");
}

#[test]
fn the_darwin64_dylib_is_universal_exports_the_fmi2_functions_and_links_libsystem_alone() {
    let dylib = built("universal2-apple-darwin", "libtensegrity_fmu_binary.dylib");
    let headers = stdout(
        Command::new("llvm-objdump")
            .args(["--macho", "--universal-headers"])
            .arg(&dylib),
    );
    let archs: Vec<&str> = headers
        .lines()
        .filter_map(|l| l.trim().strip_prefix("architecture "))
        .collect();
    assert_eq!(archs, ["x86_64", "arm64"], "{headers}");
    let expected: BTreeSet<String> = fmi2_functions().iter().map(|f| format!("_{f}")).collect();
    for arch in archs {
        let symbols = stdout(
            Command::new("llvm-nm")
                .args(["--extern-only", "--defined-only", "--just-symbol-name"])
                .arg(format!("--arch={arch}"))
                .arg(&dylib),
        );
        let exported: BTreeSet<String> = symbols.lines().map(str::to_string).collect();
        assert_eq!(exported, expected, "{arch}");
        let used = stdout(
            Command::new("llvm-objdump")
                .args(["--macho", "--dylibs-used"])
                .arg(format!("--arch={arch}"))
                .arg(&dylib),
        );
        // The macOS it needs at least, as docs/fmu.md gives it.
        let headers = stdout(
            Command::new("llvm-objdump")
                .args(["--macho", "--private-headers"])
                .arg(format!("--arch={arch}"))
                .arg(&dylib),
        );
        let minimum = if arch == "x86_64" {
            "version 10.12"
        } else {
            "minos 11.0"
        };
        assert!(
            headers.lines().any(|l| l.trim() == minimum),
            "{arch}: {minimum}"
        );
        // The file name, the library's own install name, then the libraries it loads.
        let libraries: Vec<&str> = used
            .lines()
            .skip(1)
            .filter_map(|l| l.split_whitespace().next())
            .collect();
        assert!(
            libraries[0].ends_with("/libtensegrity_fmu_binary.dylib"),
            "{used}"
        );
        assert_eq!(
            libraries[1..],
            ["/usr/lib/libSystem.B.dylib"],
            "{arch}: {used}"
        );
    }
}

#[test]
fn the_aarch64_linux_library_exports_the_fmi2_functions_alone() {
    let so = built("aarch64-unknown-linux-gnu", "libtensegrity_fmu_binary.so");
    let header = stdout(Command::new("llvm-objdump").arg("-f").arg(&so));
    assert!(
        header.contains("file format elf64-littleaarch64"),
        "{header}"
    );
    let symbols = stdout(
        Command::new("llvm-nm")
            .args([
                "--dynamic",
                "--extern-only",
                "--defined-only",
                "--just-symbol-name",
            ])
            .arg(&so),
    );
    let exported: BTreeSet<String> = symbols.lines().map(str::to_string).collect();
    assert_eq!(exported, fmi2_functions());
}
