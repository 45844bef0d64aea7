"""`tensegrity-fmu render --csv` draws a run fmpy recorded and saved with
`fmpy.util.write_csv` (quoted names, `str()` numbers): the same picture as from
`simulate`'s CSV of the same run, and an animation of its rows."""

import subprocess

from fmpy import simulate_fmu
from fmpy.util import write_csv


def test_render_reads_fmpy_csv(cli, fmus, tmp_path):
    fmu = fmus.builtin("prism2-elastic")
    result = simulate_fmu(str(fmu.path), stop_time=0.5, output_interval=0.05, output=fmu.outputs)
    fmpy_csv = tmp_path / "fmpy.csv"
    write_csv(fmpy_csv, result)
    assert fmpy_csv.read_text().startswith('"time","node[1].x"')
    ours = tmp_path / "ours.csv"
    subprocess.run(
        [cli, "simulate", "prism2-elastic", "--time", "0.5", "--interval", "0.05", "-o", ours],
        check=True,
        capture_output=True,
    )
    pictures = {}
    for name, csv in [("fmpy", fmpy_csv), ("ours", ours)]:
        png = tmp_path / f"{name}.png"
        subprocess.run(
            [cli, "render", "prism2-elastic", "--csv", csv, "--at", "0.5", "-o", png],
            check=True,
            capture_output=True,
        )
        pictures[name] = png.read_bytes()
    assert pictures["fmpy"].startswith(b"\x89PNG\r\n\x1a\n")
    assert pictures["fmpy"] == pictures["ours"]
    gif = tmp_path / "fmpy.gif"
    subprocess.run(
        [cli, "render", "prism2-elastic", "--csv", fmpy_csv, "--fps", "10", "-o", gif],
        check=True,
        capture_output=True,
    )
    assert gif.read_bytes().startswith(b"GIF89a")
