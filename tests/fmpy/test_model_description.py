"""modelDescription.xml, the archive and the documentation of the built FMUs (issue 3, items 5-7)."""

import datetime
import math
import os
import subprocess
import tomllib
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from conftest import BUILTINS
from effects_scenes import expected_variables

# A class-3 joint (node 4 is shared by three bars), mixing elastic cables (one damped, one
# not) with a force-density controlled cable whose start value the scene gives.
CLASS_K_SCENE = """\
name = "classk-tripod"
description = "three bars meeting at one class-3 joint, written by the pytest suite"
nodes = [[1.0, 0.0, 0.0], [-0.5, 0.8660254037844386, 0.0], [-0.5, -0.8660254037844386, 0.0], [0.0, 0.0, 1.0]]
force_inputs = [4]

[[bars]]
nodes = [1, 4]
mass = 1.0

[[bars]]
nodes = [2, 4]
mass = 1.5

[[bars]]
nodes = [3, 4]
mass = 2.0

[[cables]]
nodes = [1, 2]
stiffness = 100.0
rest_length = 1.6

[[cables]]
nodes = [2, 3]
control = "force_density"
force_density = 3.25

[[cables]]
nodes = [3, 1]
stiffness = 120.0
rest_length = 1.55
damping = 2.5

[solver]
step_size = 0.0005
correction = false
"""

# SI base-unit exponents (kg, m, s) of every unit the issue asks for.
UNITS = {
    "m": (0, 1, 0),
    "m/s": (0, 1, -1),
    "N": (1, 1, -2),
    "N/m": (1, 0, -2),
    "kg": (1, 0, 0),
    "s": (0, 0, 1),
    "J": (1, 2, -2),
}


@pytest.fixture(params=BUILTINS)
def builtin(request, fmus):
    return fmus.builtin(request.param)


@pytest.fixture
def classk(fmus):
    return fmus.from_toml(CLASS_K_SCENE)


def test_validate_fmu_reports_no_problem_for_builtin(builtin):
    assert validate_fmu(str(builtin.path)) == []


def test_validate_fmu_reports_no_problem_for_class_k_scene(classk):
    assert validate_fmu(str(classk.path)) == []
    assert classk.md.modelName == "classk-tripod"
    assert classk.md.coSimulation.modelIdentifier == "classk_tripod"


def test_header_is_fmi2_with_structured_names(builtin):
    assert builtin.md.fmiVersion == "2.0"
    assert builtin.md.variableNamingConvention == "structured"
    assert builtin.md.modelName == builtin.scene["name"]


def test_units_declared_with_si_base_units(builtin):
    declared = {u.name: u.baseUnit for u in builtin.md.unitDefinitions}
    for name, (kg, m, s) in UNITS.items():
        assert name in declared, f"unit {name} not declared"
        b = declared[name]
        assert (b.kg, b.m, b.s, b.A, b.K, b.mol, b.cd) == (kg, m, s, 0, 0, 0, 0), name
    used = {v.unit for v in builtin.md.modelVariables if v.unit}
    assert used <= set(declared), used - set(declared)


def test_exactly_the_variables_the_scene_calls_for(builtin):
    expected = expected_variables(builtin.scene)
    assert set(builtin.variables) == set(expected)
    for name, (causality, unit) in expected.items():
        v = builtin.variables[name]
        assert v.causality == causality, name
        assert v.unit == unit, name


def test_class_k_scene_variables_damping_and_inputs(classk):
    expected = expected_variables(classk.scene)
    assert set(classk.variables) == set(expected)
    names = set(classk.variables)
    # damping exists only on the cable whose scene entry gives it
    assert "cable[3].damping" in names
    assert "cable[1].damping" not in names
    assert "cable[2].damping" not in names
    # elastic parameters only on elastic cables, the input only on the controlled one
    assert {"cable[1].stiffness", "cable[1].rest_length", "cable[3].stiffness"} <= names
    assert "cable[2].stiffness" not in names and "cable[2].rest_length" not in names
    assert "cable[2].force_density" in names
    assert "cable[1].force_density" not in names and "cable[3].force_density" not in names
    # node forces only for force_inputs nodes
    assert {"node[4].fx", "node[4].fy", "node[4].fz"} <= names
    assert not any(f"node[{i}].f{c}" in names for i in (1, 2, 3) for c in "xyz")


def test_start_values_come_from_the_scene(classk):
    v, scene = classk.variables, classk.scene
    assert float(v["cable[2].force_density"].start) == 3.25
    assert float(v["cable[1].stiffness"].start) == 100.0
    assert float(v["cable[1].rest_length"].start) == 1.6
    assert float(v["cable[3].stiffness"].start) == 120.0
    assert float(v["cable[3].rest_length"].start) == 1.55
    assert float(v["cable[3].damping"].start) == 2.5
    for k, bar in enumerate(scene["bars"], start=1):
        assert float(v[f"bar[{k}].mass"].start) == bar["mass"]
    assert float(v["solver.step_size"].start) == 0.0005
    assert v["solver.correction"].type == "Boolean"
    assert v["solver.correction"].start == "false"
    for c in "xyz":
        assert float(v[f"node[4].f{c}"].start) == 0.0


def test_builtin_parameter_starts_match_scene(builtin):
    v, scene = builtin.variables, builtin.scene
    solver = scene.get("solver", {})
    assert float(v["solver.step_size"].start) == solver.get("step_size", 0.001)
    assert v["solver.correction"].start == str(solver.get("correction", True)).lower()
    methods = {"rk4": 1, "dopri5": 2, "rattle": 3, "sdirk3": 4}
    assert v["solver.method"].type == "Integer"
    assert int(v["solver.method"].start) == methods[solver.get("method", "dopri5")]
    assert v["solver.locate_events"].type == "Boolean"
    assert v["solver.locate_events"].start == str(solver.get("locate_events", True)).lower()
    assert float(v["solver.rtol"].start) == solver.get("rtol", 1e-6)
    assert float(v["solver.atol"].start) == solver.get("atol", 1e-9)
    for k, bar in enumerate(scene["bars"], start=1):
        assert float(v[f"bar[{k}].mass"].start) == bar["mass"]
    for j, cable in enumerate(scene.get("cables", []), start=1):
        if "stiffness" in cable:
            assert float(v[f"cable[{j}].stiffness"].start) == cable["stiffness"]


def test_causality_variability_initial_combinations(builtin, classk):
    for fmu in (builtin, classk):
        root = ET.fromstring(zipfile.ZipFile(fmu.path).read("modelDescription.xml"))
        for sv in root.iter("ScalarVariable"):
            name, caus = sv.get("name"), sv.get("causality")
            typ = sv[0]
            if caus == "output":
                assert sv.get("variability") == "continuous", name
                assert sv.get("initial") == "calculated", name
                assert typ.get("start") is None, name
            elif caus == "input":
                assert sv.get("variability") == "continuous", name
                assert sv.get("initial") is None, name  # no initial allowed for inputs
                assert typ.get("start") is not None and math.isfinite(float(typ.get("start"))), name
            elif caus == "parameter":
                assert sv.get("variability") in ("fixed", "tunable"), name
                assert sv.get("initial") == "exact", name
                assert typ.get("start") is not None, name
            else:
                pytest.fail(f"{name}: unexpected causality {caus}")


def test_model_structure_outputs_and_initial_unknowns(builtin):
    md = builtin.md
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    assert [u.variable.name for u in md.outputs] == outputs
    needing = [
        v.name
        for v in md.modelVariables
        if (v.causality == "output" and v.initial in ("approx", "calculated"))
        or (v.causality == "calculatedParameter")
    ]
    assert sorted(u.variable.name for u in md.initialUnknowns) == sorted(needing)
    root = ET.fromstring(zipfile.ZipFile(builtin.path).read("modelDescription.xml"))
    structure = [child.tag for child in root.find("ModelStructure")]
    assert structure == ["Outputs", "InitialUnknowns"]
    for child in root.find("ModelStructure"):
        assert len(child) > 0, f"empty <{child.tag}/>"


def test_default_experiment_present(builtin):
    de = builtin.md.defaultExperiment
    assert de is not None
    start, stop, step = float(de.startTime), float(de.stopTime), float(de.stepSize)
    assert start == 0.0 and stop > start
    # A communication step of 10 ms, or ten internal steps if that is longer.
    assert step == max(0.01, 10 * builtin.scene.get("solver", {}).get("step_size", 0.001))
    assert stop == 1.0


def test_co_simulation_capabilities(builtin):
    cs = builtin.md.coSimulation
    assert cs.modelIdentifier
    assert cs.canHandleVariableCommunicationStepSize is True
    assert cs.canGetAndSetFMUstate is True
    assert cs.canSerializeFMUstate is True
    assert cs.canBeInstantiatedOnlyOncePerProcess is False


def test_log_categories_declared(builtin):
    names = [c.name for c in builtin.md.logCategories]
    assert len(names) == len(set(names)) >= 1
    assert {"logStatusWarning", "logStatusError"} <= set(names)


def test_guid_stable_for_same_scene_and_changes_with_one_mass(fmus, tmp_path):
    base = fmus.builtin("prism2").scene_text
    assert "mass = 1.0" in base
    heavier = base.replace("mass = 1.0", "mass = 1.25", 1)
    (tmp_path / "a.toml").write_text(base)
    (tmp_path / "b.toml").write_text(heavier)
    g1 = read_model_description(str(fmus.fresh(str(tmp_path / "a.toml"), "guid_a1"))).guid
    g2 = read_model_description(str(fmus.fresh(str(tmp_path / "a.toml"), "guid_a2"))).guid
    g3 = read_model_description(str(fmus.fresh(str(tmp_path / "b.toml"), "guid_b"))).guid
    assert g1 == g2
    assert g1 != g3
    # the built-in and its own exported scene text are the same model
    assert g1 == fmus.builtin("prism2").md.guid


def test_archive_layout(builtin):
    with zipfile.ZipFile(builtin.path) as z:
        names = z.namelist()
    ident = builtin.md.coSimulation.modelIdentifier
    for required in (
        "modelDescription.xml",
        f"binaries/linux64/{ident}.so",
        "resources/scene.toml",
        "documentation/index.html",
        "model.png",
    ):
        assert required in names
    with zipfile.ZipFile(builtin.path) as z:
        assert z.read("model.png").startswith(b"\x89PNG\r\n\x1a\n")
    for n in names:
        assert not n.startswith("/") and not n.startswith("."), n
        assert "\\" not in n, n
        assert ".." not in n.split("/"), n


def test_default_build_is_prism2(cli, tmp_path):
    res = subprocess.run([str(cli), "build"], cwd=tmp_path, check=True, capture_output=True, text=True)
    path = tmp_path / res.stdout.strip()
    assert path.is_file()
    with zipfile.ZipFile(path) as z:
        assert "binaries/linux64/prism2.so" in z.namelist()
    assert validate_fmu(str(path)) == []


def test_documentation_lists_every_variable_with_unit(builtin, classk):
    for fmu in (builtin, classk):
        html = zipfile.ZipFile(fmu.path).read("documentation/index.html").decode()
        rows = {}
        for row in html.split("<tr>")[1:]:
            cells = [c.split("</td>")[0] for c in row.split("<td>")[1:]]
            if cells:
                name = cells[0].replace("<code>", "").replace("</code>", "")
                rows[name] = cells
        for v in fmu.md.modelVariables:
            assert v.name in rows, f"{v.name} missing from documentation/index.html"
            if v.unit:
                assert v.unit in rows[v.name], f"{v.name}: unit {v.unit} not shown"
            assert v.description and v.description.split()[0] in html


# --- issue 10: what importers need (items 7-9) ------------------------------------------

REPO = Path(__file__).resolve().parents[2]

# The class-k tripod with a sinusoidal load (a phase in rad), gravity and a point mass.
LOADED_SCENE = CLASS_K_SCENE.replace(
    "[[bars]]",
    """gravity = [0.0, 0.0, -9.81]

[[loads]]
kind = "sinusoidal"
node = 4
amplitude = [1.0, 0.0, 0.0]
frequency = 2.0
phase = 0.25

[[point_masses]]
node = 4
mass = 0.5

[[bars]]""",
    1,
)


@pytest.fixture
def loaded(fmus):
    return fmus.from_toml(LOADED_SCENE)


def test_version_license_and_author_from_cargo_toml(builtin):
    package = tomllib.loads((REPO / "Cargo.toml").read_text())["package"]
    md = builtin.md
    assert md.version == package["version"]
    assert md.license == package["license"] == "MIT OR Apache-2.0"
    assert md.author and md.copyright


def test_generation_tool_names_the_commit(builtin):
    head = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True, check=True
    ).stdout.strip()
    tool = builtin.md.generationTool
    assert tool.startswith("tensegrity-fmu "), tool
    assert f"(git {head}" in tool, f"{tool} does not name HEAD {head}"


def test_generation_date_from_source_date_epoch(cli, tmp_path):
    out = tmp_path / "dated.fmu"
    env = dict(os.environ, SOURCE_DATE_EPOCH="1700000000")
    subprocess.run([str(cli), "build", "prism2", "-o", str(out)], check=True, env=env, capture_output=True)
    assert read_model_description(str(out)).generationDateAndTime == "2023-11-14T22:13:20Z"
    assert validate_fmu(str(out)) == []
    undated = tmp_path / "now.fmu"
    env.pop("SOURCE_DATE_EPOCH")
    subprocess.run([str(cli), "build", "prism2", "-o", str(undated)], check=True, env=env, capture_output=True)
    stamp = read_model_description(str(undated)).generationDateAndTime
    built = datetime.datetime.strptime(stamp, "%Y-%m-%dT%H:%M:%SZ").replace(tzinfo=datetime.timezone.utc)
    age = datetime.datetime.now(datetime.timezone.utc) - built
    assert datetime.timedelta(0) <= age < datetime.timedelta(minutes=5), stamp


def test_rad_unit_has_its_base_unit(loaded):
    assert validate_fmu(str(loaded.path)) == []
    units = {u.name: u.baseUnit for u in loaded.md.unitDefinitions}
    rad = units["rad"]
    assert (rad.rad, rad.kg, rad.m, rad.s) == (1, 0, 0, 0)
    assert loaded.variables["load[1].phase"].unit == "rad"


def test_solver_method_and_max_steps_are_integer_parameters(builtin, open_fmu):
    v = builtin.variables
    method, steps = v["solver.method"], v["solver.max_steps"]
    assert (method.type, method.causality, method.variability) == ("Integer", "parameter", "fixed")
    assert (int(method.min), int(method.max)) == (1, 4)
    assert "1 = rk4" in method.description and "4 = sdirk3" in method.description
    assert (steps.type, steps.causality, steps.variability) == ("Integer", "parameter", "tunable")
    assert int(steps.start) == builtin.scene.get("solver", {}).get("max_steps", 100000)
    assert int(steps.min) == 1
    assert not builtin.md.typeDefinitions  # no Enumeration left for libcosim to ignore
    s = open_fmu(builtin)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    vrs = s.vrs(["solver.method", "solver.max_steps"])
    s.fmu.setInteger(vrs, [2, 250])
    assert s.fmu.getInteger(vrs) == [2, 250]
    s.fmu.exitInitializationMode()
    s.step(0.01)
    assert s.fmu.getInteger(vrs) == [2, 250]


def test_max_steps_below_one_is_rejected(builtin, open_fmu):
    s = open_fmu(builtin)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    with pytest.raises(Exception):
        s.fmu.setInteger(s.vrs(["solver.max_steps"]), [0])
    assert any("solver.max_steps" in m for m in s.errors())


TUNABLE_PREFIXES = ("gravity.", "ground.", "load[", "point_mass[", "bar[")
TUNABLE_NAMES = {"solver.max_steps", "solver.rtol", "solver.atol"}
FIXED_NAMES = {"solver.step_size", "solver.method", "solver.correction", "solver.locate_events"}


def test_tunable_parameters(builtin, loaded):
    for fmu in (builtin, loaded):
        for v in fmu.md.modelVariables:
            if v.causality != "parameter":
                continue
            cable_setting = v.name.startswith("cable[") and v.name.split(".")[1] in (
                "stiffness", "rest_length", "damping")
            if v.name in FIXED_NAMES:
                assert v.variability == "fixed", v.name
            else:
                assert v.name in TUNABLE_NAMES or v.name.startswith(TUNABLE_PREFIXES) or cable_setting, v.name
                assert v.variability == "tunable", v.name
            assert v.initial in (None, "exact"), v.name
    names = {v.name for v in loaded.md.modelVariables if v.variability == "tunable"}
    assert {"gravity.z", "load[1].phase", "point_mass[1].mass", "cable[3].damping"} <= names


def test_libcosim_sees_and_sets_the_solver_method(fmus):
    """libcosim (OSP) ignores Enumerations: solver.method must reach it as an Integer."""
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    fmu = fmus.builtin("prism2")
    execution = CosimExecution.from_step_size(step_size=10_000_000)  # 10 ms in ns
    slave = CosimLocalSlave(fmu_path=str(fmu.path), instance_name="p")  # outlives its use
    index = execution.add_local_slave(slave)
    integers = {
        v.name.decode(): v.reference
        for v in execution.slave_variables(slave_index=index)
        if v.type == CosimVariableType.INTEGER.value
    }
    assert set(integers) == {"solver.method", "solver.max_steps"}
    assert integers["solver.method"] == fmu.vr["solver.method"]
    assert execution.integer_initial_value(
        slave_index=index, variable_reference=integers["solver.method"], value=3
    )
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer=observer)
    assert execution.simulate_until(target_time=50_000_000)
    refs = [integers["solver.method"], integers["solver.max_steps"]]
    assert observer.last_integer_values(slave_index=index, variable_references=refs) == [3, 100000]
