//! The FMU's binaries for other platforms run here: the win64 DLL under Wine and the
//! aarch64-linux library under QEMU, each through the C importer of tests/importer/ built
//! for its platform, give the node positions of the linux64 binary after 1 s of prism2
//! and tower20. Each also runs its portable (scalar) kernels when `TENSEGRITY_SIMD=scalar`
//! asks for them, with the same positions. Needs `bash tests/setup.sh` (wine64, mingw-w64,
//! qemu-user, the rustup targets) and `bash fmu/build-binary.sh`.

mod platform_support;

use platform_support::{
    extracted, max_difference, positions, positions_at, simulate, Extracted, Runner,
};

/// The agreement the platforms must reach, m.
const TOLERANCE: f64 = 1e-12;

fn compare(fmu: &Extracted, runner: Runner) {
    let linux = positions(fmu, Runner::Native, &[]);
    let other = positions(fmu, runner, &[]);
    let diff = max_difference(&linux.positions, &other.positions);
    eprintln!(
        "{}: {runner:?} vs linux64, {} coordinates, largest difference {diff:e} m",
        fmu.dir.display(),
        fmu.positions.len()
    );
    assert!(
        diff <= TOLERANCE,
        "{runner:?}: {diff:e} m > {TOLERANCE:e} m"
    );
    // The pushed structure moved (the comparison is not of start positions only).
    let start = positions_at(fmu, Runner::Native, "0", &[]);
    assert!(max_difference(&start.positions, &linux.positions) > 1e-6);
}

#[test]
fn the_win64_binary_under_wine_gives_the_linux64_positions() {
    for scene in ["prism2", "tower20"] {
        compare(extracted(scene), Runner::Wine);
    }
}

#[test]
fn the_aarch64_binary_under_qemu_gives_the_linux64_positions() {
    for scene in ["prism2", "tower20"] {
        compare(extracted(scene), Runner::Qemu);
    }
}

/// What the default run of `runner` logs as its kernels on this processor.
fn default_kernels(runner: Runner) -> &'static str {
    if runner == Runner::Qemu {
        "kernels: scalar (not x86-64)"
    } else if std::arch::is_x86_feature_detected!("avx2") {
        "kernels: avx2"
    } else {
        "kernels: scalar (the processor has no AVX2)"
    }
}

#[test]
fn tensegrity_simd_scalar_forces_the_portable_kernels_with_the_same_positions() {
    let fmu = extracted("tower20");
    for runner in [Runner::Native, Runner::Wine, Runner::Qemu] {
        let auto = positions(fmu, runner, &[]);
        let scalar = positions(fmu, runner, &[("TENSEGRITY_SIMD", "scalar")]);
        assert!(
            auto.log.contains(default_kernels(runner)),
            "{runner:?}: {}",
            auto.log
        );
        assert!(
            scalar
                .log
                .contains("kernels: scalar (TENSEGRITY_SIMD=scalar)"),
            "{runner:?}: {}",
            scalar.log
        );
        // The two copies of each kernel give the same bits (FMA off in both).
        assert_eq!(auto.positions, scalar.positions, "{runner:?}");
    }
}

#[test]
fn a_bad_tensegrity_simd_value_fails_fmi2instantiate_naming_it() {
    let fmu = extracted("prism2");
    let out = simulate(fmu, Runner::Native, "1", &[("TENSEGRITY_SIMD", "fast")]);
    assert!(!out.status.success());
    let log = String::from_utf8_lossy(&out.stderr);
    assert!(
        log.contains(
            "fmi2Instantiate: TENSEGRITY_SIMD=fast is not a kernel choice: set it to `scalar` \
             or `auto`, or unset it"
        ),
        "{log}"
    );
}
