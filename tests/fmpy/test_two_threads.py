"""A large structure's FMU evaluates on two threads (issue 14): the second thread lives and
dies with its instance (and its saved states), and the results are the CLI's, bit for bit.
"""

import csv
import math
import os
import subprocess

import numpy as np

STAGES = 1400  # 4,200 bars: beyond the side-by-side lanes, on two threads


def tower_toml(stages: int) -> str:
    """A class-2 tower of `stages` stages (the built-in towers' geometry), elastic cables at
    98 % of their lengths, rk4 at 1 ms, node positions as its only outputs."""
    r, h = 1 / math.sqrt(3), 0.5 + math.sqrt(3) / 6
    nodes = [
        [r * math.cos(math.radians(ring * 150 + i * 120)),
         r * math.sin(math.radians(ring * 150 + i * 120)), ring * h]
        for ring in range(stages + 1) for i in range(3)
    ]
    node = lambda ring, i: 3 * ring + i + 1  # noqa: E731
    lines = [
        f'name = "tower{stages}"',
        "nodes = [" + ", ".join(f"[{x!r}, {y!r}, {z!r}]" for x, y, z in nodes) + "]",
        "fixed = [1, 2, 3]",
        "force_inputs = [" + ", ".join(str(node(stages, i)) for i in range(3)) + "]",
        'outputs = ["positions"]',
    ]
    for k in range(stages):
        for i in range(3):
            lines += ["[[bars]]", f"nodes = [{node(k, i)}, {node(k + 1, i)}]", "mass = 1.0"]

    def cable(a, b):
        rest = 0.98 * math.dist(nodes[a - 1], nodes[b - 1])
        return ["[[cables]]", f"nodes = [{a}, {b}]", "stiffness = 500.0", f"rest_length = {rest!r}"]

    for ring in range(stages + 1):
        for i in range(3):
            lines += cable(node(ring, i), node(ring, (i + 1) % 3))
    for k in range(stages):
        for i in range(3):
            lines += cable(node(k, i), node(k + 1, (i + 2) % 3))
    lines += ["[solver]", 'method = "rk4"', "step_size = 0.001"]
    return "\n".join(lines) + "\n"


def threads() -> int:
    return len(os.listdir("/proc/self/task"))


def test_the_second_thread_lives_with_its_instance_and_gives_the_clis_bits(
    fmus, open_fmu, cli, tmp_path
):
    text = tower_toml(STAGES)
    fmu = fmus.from_toml(text)
    before = threads()
    slave = open_fmu(fmu, name="big").init(inputs={f"node[{3 * STAGES + 1}].fx": 2.0})
    start = slave.outputs()
    slave.run(10, 0.001)
    assert threads() == before + 1, "the instance's second thread"
    # A saved state is a copy of the instance: it starts no thread until it steps.
    state = slave.fmu.getFMUstate()
    slave.run(10, 0.001)
    after_20 = slave.outputs()
    slave.fmu.setFMUstate(state)
    slave.time = 0.01
    slave.run(10, 0.001)
    assert np.array_equal(slave.outputs(), after_20), "restored and stepped again"
    slave.fmu.freeFMUstate(state)
    assert threads() <= before + 1

    # The CLI's run of the same scene and input, on two threads too.
    scene = tmp_path / "tower.toml"
    scene.write_text(text)
    inputs = tmp_path / "inputs.csv"
    inputs.write_text(f"time,node[{3 * STAGES + 1}].fx\n0,2.0\n0.02,2.0\n")
    out = tmp_path / "out.csv"
    subprocess.run(
        [str(cli), "simulate", str(scene), "--time", "0.02", "--interval", "0.02",
         "--inputs", str(inputs), "-o", str(out)],
        check=True, capture_output=True,
    )
    with open(out) as f:
        rows = list(csv.DictReader(f))
    assert float(rows[-1]["time"]) == 0.02
    cli_final = np.array([float(rows[-1][name]) for name in fmu.outputs])
    assert np.abs(after_20 - start).max() > 1e-4, "the tower moved"
    assert np.array_equal(after_20, cli_final), np.abs(after_20 - cli_final).max()

    slave.free()
    assert threads() == before, "the second thread is joined when the instance is freed"
