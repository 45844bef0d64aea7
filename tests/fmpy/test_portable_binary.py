"""The shipped FMU binary loads on glibc 2.28 and newer (RHEL 8/9, Ubuntu 20.04; issue 10).

The dynamic loader refuses a library whose version needs (`.gnu.version_r`) name a GLIBC_x.y
that the system's libc lacks, so those needs are read from the binary inside built FMUs
(pyelftools) and checked against 2.28. A binary linked on this Debian (glibc 2.36) against its
own libc needs GLIBC_2.35 (`hypot`) and fails the check; fmu/build-binary.sh links with
cargo-zigbuild against glibc 2.28 stubs.
"""

import io
import re
import shutil
import zipfile

import numpy as np
import pytest
from elftools.elf.elffile import ELFFile

from conftest import BUILTINS, LIBRARY, PORTABLE

OLDEST = (2, 28)


def glibc_needs(data: bytes) -> dict:
    """{(x, y): [symbols]} for every GLIBC_x.y version the binary requires of the loader."""
    elf = ELFFile(io.BytesIO(data))
    verneed = elf.get_section_by_name(".gnu.version_r")
    assert verneed is not None, "no version needs: not a glibc-linked shared library"
    index = {}  # version index (vna_other) -> (x, y)
    for _, auxiliaries in verneed.iter_versions():
        for aux in auxiliaries:
            m = re.fullmatch(r"GLIBC_(\d+)\.(\d+)(?:\.\d+)?", aux.name)
            if m:
                index[aux.entry["vna_other"]] = (int(m[1]), int(m[2]))
    needs = {v: [] for v in index.values()}
    versym = elf.get_section_by_name(".gnu.version")
    for i, sym in enumerate(elf.get_section_by_name(".dynsym").iter_symbols()):
        ndx = versym.get_symbol(i)["ndx"]
        if isinstance(ndx, int) and (ndx & 0x7FFF) in index and sym["st_shndx"] == "SHN_UNDEF":
            needs[index[ndx & 0x7FFF]].append(sym.name)
    return needs


def shipped_binary(fmu) -> bytes:
    with zipfile.ZipFile(fmu.path) as z:
        return z.read(f"binaries/linux64/{fmu.md.coSimulation.modelIdentifier}.so")


@pytest.mark.parametrize("name", BUILTINS)
def test_shipped_binary_needs_at_most_glibc_2_28(fmus, name):
    data = shipped_binary(fmus.builtin(name))
    needs = glibc_needs(data)
    assert (2, 2) in needs, f"the parser found no GLIBC_2.2.5 base version: {sorted(needs)}"
    too_new = {f"GLIBC_{x}.{y}": syms for (x, y), syms in needs.items() if (x, y) > OLDEST}
    assert not too_new, f"the FMU binary needs glibc newer than 2.28: {too_new}"
    print(f"{name}: highest GLIBC_{max(needs)[0]}.{max(needs)[1]}, {len(data)} bytes")


def test_shipped_binary_is_the_portable_build(fmus):
    """`tensegrity-fmu build` packages fmu/build-binary.sh's library, not cargo's native one."""
    assert PORTABLE.is_file(), "run fmu/build-binary.sh"
    portable = PORTABLE.read_bytes()
    for name in BUILTINS:
        assert shipped_binary(fmus.builtin(name)) == portable, (
            f"{name}.fmu does not ship {PORTABLE} (stale? run fmu/build-binary.sh after changing the sources)"
        )
    native = LIBRARY.read_bytes()
    assert portable != native
    for label, data in (("native", native), ("portable", portable)):
        x, y = max(glibc_needs(data))
        print(f"{label}: highest GLIBC_{x}.{y}, {len(data)} bytes")


def test_portable_binary_steps_like_the_native_one(fmus, open_fmu, tmp_path):
    """Both libraries, loaded side by side in this process, step tower20 under a top force
    to the same bits (same Rust code; only the glibc symbol versions they link differ)."""
    fmu = fmus.builtin("tower20")
    native_dir = tmp_path / "native"
    shutil.copytree(fmu.dir, native_dir)
    shutil.copyfile(LIBRARY, native_dir / "binaries" / "linux64" / fmu.library.name)
    node = fmu.scene["force_inputs"][0]
    runs = []
    for directory in (fmu.dir, str(native_dir)):
        s = open_fmu(fmu, name=f"run{len(runs)}", directory=directory)
        s.init(inputs={f"node[{node}].fx": 20.0, f"node[{node}].fz": -30.0})
        s.run(300, 1e-3)
        runs.append(s.outputs())
    moved = runs[0][fmu.outputs.index(f"node[{node}].x")] - fmu.scene["nodes"][node - 1][0]
    assert abs(moved) > 1e-4, "the force input moved nothing: the comparison would be vacuous"
    assert np.array_equal(runs[0], runs[1]), np.max(np.abs(runs[0] - runs[1]))
