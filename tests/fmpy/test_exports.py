"""The FMU binary exports exactly the FMI 2.0 co-simulation functions: all of them, and
nothing else (no symbol of a dependency). Those it does not support return fmi2Error with a
logged message saying so and what to do instead."""

import os
import re
from pathlib import Path

import pytest
from elftools.elf.elffile import ELFFile
from fmpy.fmi1 import FMICallException

from conftest import LIBRARY, PORTABLE

# The common and co-simulation functions of the FMI 2.0 standard.
STANDARD = {
    "fmi2GetTypesPlatform", "fmi2GetVersion", "fmi2SetDebugLogging", "fmi2Instantiate",
    "fmi2FreeInstance", "fmi2SetupExperiment", "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode", "fmi2Terminate", "fmi2Reset", "fmi2GetReal", "fmi2GetInteger",
    "fmi2GetBoolean", "fmi2GetString", "fmi2SetReal", "fmi2SetInteger", "fmi2SetBoolean",
    "fmi2SetString", "fmi2GetFMUstate", "fmi2SetFMUstate", "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate", "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative",
    "fmi2SetRealInputDerivatives", "fmi2GetRealOutputDerivatives", "fmi2DoStep", "fmi2CancelStep",
    "fmi2GetStatus", "fmi2GetRealStatus", "fmi2GetIntegerStatus", "fmi2GetBooleanStatus",
    "fmi2GetStringStatus",
}


def header_functions():
    """The functions fmi2Functions.h (in the fmi-sys crate's sources) declares outside its
    Model Exchange section."""
    home = Path(os.environ.get("CARGO_HOME", Path.home() / ".cargo"))
    headers = sorted(home.glob("registry/src/*/fmi-sys-0.6.0/fmi-standard2/headers/fmi2Functions.h"))
    assert headers, f"fmi-sys 0.6.0's headers are not under {home}/registry/src"
    text = headers[0].read_text()
    declarations = text[text.rindex("Common Functions") :]
    model_exchange = declarations.index("Functions for FMI2 for Model Exchange")
    co_simulation = declarations.index("Functions for FMI2 for Co-Simulation")
    kept = declarations[:model_exchange] + declarations[co_simulation:]
    return set(re.findall(r"FMI2_Export\s+\w+TYPE\s+(\w+);", kept))


def exported(data_path: Path):
    """Names of the defined global symbols in the dynamic symbol table."""
    with open(data_path, "rb") as f:
        elf = ELFFile(f)
        return {
            s.name
            for s in elf.get_section_by_name(".dynsym").iter_symbols()
            if s.name
            and s["st_shndx"] != "SHN_UNDEF"
            and s["st_info"]["bind"] in ("STB_GLOBAL", "STB_WEAK")
        }


def test_the_list_is_the_standards():
    assert header_functions() == STANDARD


@pytest.mark.parametrize("path", [LIBRARY, PORTABLE], ids=["cargo", "portable"])
def test_binary_exports_exactly_the_standard_functions(cli, path):
    names = exported(path)
    assert names - STANDARD == set(), "exported beside the standard's functions"
    assert STANDARD - names == set(), "standard functions not exported"


def test_shipped_binary_exports_exactly_the_standard_functions(fmus, tmp_path):
    fmu = fmus.builtin("prism2")
    so = Path(fmu.dir) / "binaries" / "linux64" / f"{fmu.md.coSimulation.modelIdentifier}.so"
    assert exported(so) == STANDARD


@pytest.mark.parametrize(
    "call,advice",
    [
        (lambda f, x, fx: f.getDirectionalDerivative([x], [fx], [1.0]), "`linearize` command"),
        (lambda f, x, fx: f.setRealInputDerivatives([fx], [1], [0.0]), "fmi2SetReal before each fmi2DoStep"),
        (lambda f, x, fx: f.getRealOutputDerivatives([x], [1]), "read the outputs with fmi2GetReal"),
        (lambda f, x, fx: f.cancelStep(), "use fmi2SetFMUstate or fmi2Reset to go back"),
        (lambda f, x, fx: f.getStatus(0), "its return value is the status"),
        (lambda f, x, fx: f.getIntegerStatus(0), "use fmi2GetRealStatus or fmi2GetBooleanStatus"),
        (lambda f, x, fx: f.getStringStatus(4), "its return value is the status"),
    ],
    ids=[
        "fmi2GetDirectionalDerivative", "fmi2SetRealInputDerivatives", "fmi2GetRealOutputDerivatives",
        "fmi2CancelStep", "fmi2GetStatus", "fmi2GetIntegerStatus", "fmi2GetStringStatus",
    ],
)
def test_unsupported_function_returns_error_saying_so(fmus, open_fmu, request, call, advice):
    name = request.node.callspec.id
    fmu = fmus.builtin("prism2")
    s = open_fmu(fmu).init()
    s.run(2, 0.001)
    x, fx = s.vrs(["node[7].x", "node[7].fx"])
    with pytest.raises(FMICallException) as e:
        call(s.fmu, x, fx)
    assert e.value.status == 3  # fmi2Error
    message = s.errors()[-1]
    assert message.startswith(f"{name}: not supported"), message
    assert advice in message, message
    s.run(2, 0.001)  # a refused call leaves the instance running
