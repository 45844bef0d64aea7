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
