"""tests/rebuilt.sh, which tests/run.sh runs after each cargo step: on a real cargo log of a
small crate, it names the file whose change made cargo rebuild, and says nothing when cargo
built for the first time or found everything fresh."""

import os
import subprocess

from conftest import REPO

REBUILT = REPO / "tests" / "rebuilt.sh"


def cargo_build_log(crate, log):
    env = dict(os.environ, CARGO_LOG="cargo::core::compiler::fingerprint=info", RUST_BACKTRACE="0")
    res = subprocess.run(["cargo", "build", "--offline", "--manifest-path", str(crate / "Cargo.toml")],
                         env=env, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    log.write_text(res.stderr)
    report = subprocess.run(["bash", str(REBUILT), str(log)], capture_output=True, text=True)
    assert report.returncode == 0, report.stderr
    return res.stderr, report.stdout


def test_rebuilt_names_the_changed_file_and_is_silent_otherwise(tmp_path):
    crate = tmp_path / "tiny"
    (crate / "src").mkdir(parents=True)
    (crate / "Cargo.toml").write_text('[package]\nname = "tiny"\nversion = "0.1.0"\nedition = "2021"\n')
    main = crate / "src" / "main.rs"
    main.write_text("fn main() {}\n")
    log = tmp_path / "cargo.log"

    cargo, report = cargo_build_log(crate, log)  # first build: nothing was built before
    assert "Compiling tiny" in cargo and report == ""

    main.write_text("fn main() {}\n// changed\n")
    cargo, report = cargo_build_log(crate, log)
    assert "Compiling tiny" in cargo
    lines = report.strip().splitlines()
    assert lines[0] == "!! cargo rebuilt what it had built before:"
    assert lines[1:] == [f'!!   tiny v0.1.0 Build "tiny": changed "{main}"'], report

    cargo, report = cargo_build_log(crate, log)  # nothing changed
    assert "Compiling" not in cargo and report == ""


def test_rebuilt_names_a_unit_built_over_a_dependency_with_other_features(tmp_path):
    """A `cargo build -p` of one crate with other features, then a workspace build: the
    cdylib, one output for both, is rebuilt, and the report says so (the way a test's
    `cargo build -p` of the FMU crate once undid the workspace build)."""
    (tmp_path / "Cargo.toml").write_text('[workspace]\nmembers = ["dep", "tiny"]\nresolver = "2"\n')
    (tmp_path / "dep" / "src").mkdir(parents=True)
    (tmp_path / "dep" / "Cargo.toml").write_text(
        '[package]\nname = "dep"\nversion = "0.1.0"\nedition = "2021"\n[features]\nextra = []\n')
    (tmp_path / "dep" / "src" / "lib.rs").write_text(
        'pub fn f() -> u32 { if cfg!(feature = "extra") { 2 } else { 1 } }\n')
    (tmp_path / "tiny" / "src").mkdir(parents=True)
    (tmp_path / "tiny" / "Cargo.toml").write_text(
        '[package]\nname = "tiny"\nversion = "0.1.0"\nedition = "2021"\n[lib]\ncrate-type = ["cdylib"]\n'
        '[dependencies]\ndep = { path = "../dep" }\n')
    (tmp_path / "tiny" / "src" / "lib.rs").write_text('#[no_mangle]\npub extern "C" fn g() -> u32 { dep::f() }\n')
    log = tmp_path / "cargo.log"
    env = dict(os.environ, CARGO_LOG="cargo::core::compiler::fingerprint=info", RUST_BACKTRACE="0")

    def build(*args):
        res = subprocess.run(["cargo", "build", "--offline", *args], cwd=tmp_path, env=env,
                             capture_output=True, text=True, timeout=120)
        assert res.returncode == 0, res.stderr
        log.write_text(res.stderr)
        report = subprocess.run(["bash", str(REBUILT), str(log)], capture_output=True, text=True)
        assert report.returncode == 0, report.stderr
        return res.stderr, report.stdout

    assert build("--workspace")[1] == ""
    build("-p", "tiny", "--features", "dep/extra")
    cargo, report = build("--workspace")
    assert "Compiling tiny" in cargo
    lines = report.strip().splitlines()
    assert lines[0] == "!! cargo rebuilt what it had built before:", report
    assert lines[1].startswith('!!   tiny v0.1.0 Build lib "tiny": built against another build of a dependency'), report
    cargo, report = build("--workspace")  # nothing changed since
    assert "Compiling" not in cargo and report == ""
