"""The platform folders of an FMU built with every binary (`bash fmu/build-binary.sh`), as
fmpy sees them: `read_model_description` reads the one modelDescription.xml they share, and
`supported_platforms` finds linux64, win64 and darwin64. fmpy 0.3.32 knows no folder for
Linux on ARM in FMI 2.0 (it looks in linux64 there), so `aarch64-linux`, the FMI 3.0 name
it uses for FMI 3.0 FMUs, is in the archive but not in its list."""

import subprocess
import zipfile

from fmpy import read_model_description, supported_platforms
from fmpy.validation import validate_fmu

FOLDERS = {
    "linux64": "so",
    "win64": "dll",
    "darwin64": "dylib",
    "aarch64-linux": "so",
}


def build(cli, tmp_path, *args):
    out = tmp_path / "prism2.fmu"
    subprocess.run(
        [str(cli), "build", "prism2", "-o", str(out), *args],
        check=True,
        capture_output=True,
        text=True,
    )
    return out


def test_fmpy_sees_every_platform_folder(cli, tmp_path):
    fmu = build(cli, tmp_path)
    with zipfile.ZipFile(fmu) as z:
        binaries = sorted(n for n in z.namelist() if n.startswith("binaries/"))
    expected = sorted(f"binaries/{p}/prism2.{e}" for p, e in FOLDERS.items())
    assert binaries == expected, "run `bash fmu/build-binary.sh` for every platform"
    assert sorted(supported_platforms(str(fmu))) == ["darwin64", "linux64", "win64"]
    md = read_model_description(str(fmu))
    assert md.coSimulation.modelIdentifier == "prism2"
    assert validate_fmu(str(fmu)) == []


def test_platforms_flag_chooses_the_folders(cli, tmp_path):
    fmu = build(cli, tmp_path, "--platforms", "linux64,win64")
    assert sorted(supported_platforms(str(fmu))) == ["linux64", "win64"]
    with zipfile.ZipFile(fmu) as z:
        assert not any(n.startswith("binaries/darwin64/") for n in z.namelist())


def test_an_unknown_platform_is_a_one_line_error(cli, tmp_path):
    res = subprocess.run(
        [str(cli), "build", "prism2", "-o", str(tmp_path / "x.fmu"), "--platforms", "win32"],
        capture_output=True,
        text=True,
    )
    assert res.returncode != 0
    assert res.stderr == (
        "error: --platforms: unknown platform 'win32': choose from "
        "linux64,win64,darwin64,aarch64-linux\n"
    )
    assert not (tmp_path / "x.fmu").exists()


def test_binary_without_linux64_is_a_one_line_error(cli, tmp_path):
    res = subprocess.run(
        [str(cli), "build", "prism2", "-o", str(tmp_path / "x.fmu"), "--platforms", "win64",
         "--binary", "target/release/libtensegrity_fmu_binary.so"],
        capture_output=True,
        text=True,
    )
    assert res.returncode != 0
    assert res.stderr == (
        "error: --binary is the linux64 binary: add linux64 to --platforms or drop --binary\n"
    )
