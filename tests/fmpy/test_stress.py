"""Stress suite, FMU half (issue 5): every hard case run through the built FMU with fmpy.

Each test asserts finite outputs, constraint errors <= 1e-12 at every communication point where
the correction is on, and a stated physical check; it appends one JSON row per (case, method) to
$STRESS_RESULTS (default target/stress/results.jsonl) BEFORE asserting. Energy drift =
max |E(t) - E(0) - W(t)| / max(|E(0)|, kinetic, |W|), E = energy.total, W the work of the node
force inputs (piecewise constant per communication step, so W is exact). Orthogonality in m^2/s.
"""

import ctypes
import json
import math
import os
import re
import subprocess

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from conftest import REPO

RESULTS = os.environ.get("STRESS_RESULTS", str(REPO / "target" / "stress" / "results.jsonl"))
METHODS = {"rk4": 1, "dopri5": 2, "rattle": 3}
ERR = ["constraint.length_error", "constraint.orthogonality_error"]


def record(case, method, steps, tr, checks, note, rejected=False):
    """Writes the row (before any assert) and returns the failed checks."""
    failed = [k for k, ok in checks.items() if not ok]
    num = lambda x: float(x) if math.isfinite(x) else str(x)
    row = {"layer": "fmu", "case": case, "method": method, "steps": int(steps),
           "max_length_error": num(tr.max_err[0]) if tr else None,
           "max_orthogonality_error": num(tr.max_err[1]) if tr else None,
           "energy_drift": num(tr.drift()) if tr else None,
           "status": "fail" if failed else "rejected" if rejected else "pass",
           "note": note + ("; FAILED: " + "; ".join(failed) if failed else "")}
    os.makedirs(os.path.dirname(RESULTS), exist_ok=True)
    with open(RESULTS, "a") as fh:
        fh.write(json.dumps(row) + "\n")
    return failed


def verdict(failed):
    assert not failed, "; ".join(failed)


def start(open_fmu, fmu, method="rk4", params=None, inputs=None, correction=True, name="s"):
    s = open_fmu(fmu, name=name)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    s.fmu.setInteger(s.vrs(["solver.method"]), [METHODS[method]])
    s.fmu.setBoolean(s.vrs(["solver.correction"]), [int(correction)])
    s.set({"solver.rtol": 1e-9, "solver.atol": 1e-9, **(params or {}), **(inputs or {})})
    s.fmu.exitInitializationMode()
    return s


class Tracker:
    """Steps a Slave and checks every communication point: finiteness, constraint errors, energy
    balance, internal steps (from the logEvents messages) and, on an error, the kept state."""

    def __init__(self, s, keep=False, extra=()):
        sc, self.s, self.keep = s.file.scene, s, keep
        n, fin = len(sc["nodes"]), sc.get("force_inputs", [])
        self.bars = [(b["nodes"][0] - 1, b["nodes"][1] - 1, b["mass"]) for b in sc["bars"]]
        self.mass = sum(m for _, _, m in self.bars)
        self.P = [f"node[{i}].{c}" for i in range(1, n + 1) for c in "xyz"]
        self.F = [f"node[{i}].f{c}" for i in fin for c in "xyz"]
        self.fi = 3 + np.array([self.P.index(f"node[{k}].{c}") for k in fin for c in "xyz"], int)
        V = [f"node[{i}].v{c}" for i in range(1, n + 1) for c in "xyz"]
        self.names = ERR + ["energy.total"] + self.P + V + list(extra)
        self.max_err, self.work, self.dmax, self.scale, self.steps = np.zeros(2), 0.0, 0.0, 0.0, 0
        self.finite, self.hist, self.error, self.intact, self.first_bad = True, [], None, None, None
        self.lmax = max(math.dist(sc["nodes"][a], sc["nodes"][b]) for a, b, _ in self.bars)
        self.orth_floor, self.E0, self.t_hit, self.seen = 1e-12, None, None, len(s.messages)
        self.sample()

    def xv(self, o):
        n = len(self.P)
        return o[3:3 + n].reshape(-1, 3), o[3 + n:3 + 2 * n].reshape(-1, 3)

    def sample(self, force=None, x_old=None):
        o = self.last = self.s.get(self.names)
        if not np.all(np.isfinite(o)):
            self.finite = False
            return
        x, v = self.xv(o)
        if force is not None:
            self.work += float(np.dot(force, o[self.fi] - x_old))
        ke = sum(m / 6 * (v[a] @ v[a] + v[a] @ v[b] + v[b] @ v[b]) for a, b, m in self.bars)
        self.E0 = o[2] if self.E0 is None else self.E0
        self.scale = max(self.scale, abs(self.E0), ke, abs(self.work))
        self.dmax = max(self.dmax, abs(o[2] - self.E0 - self.work))
        self.max_err = np.maximum(self.max_err, o[:2])
        if self.t_hit is None and o[0] > 1e-6:
            self.t_hit = self.s.time
        # orthogonality is (va - vb).(a - b): its round-off floor grows with |v| L (only the 1e9 case)
        self.orth_floor = max(self.orth_floor, 16 * 2.2e-16 * np.abs(v).max() * math.sqrt(3) * self.lmax)
        if self.keep:
            self.hist.append(o)

    def drift(self):
        return self.dmax / self.scale if self.scale > 0 else 0.0

    def step(self, h):
        force, x_old = (np.array(self.s.get(self.F)), self.last[self.fi]) if self.F else (None, None)
        before = self.last
        try:
            self.s.step(h)
        except FMICallException:
            self.error = (self.s.time, (self.s.errors() or ["(no message)"])[-1])
            self.intact = bool(np.array_equal(self.s.get(self.names), before))
            return False
        for _, cat, m in self.s.messages[self.seen:]:
            hit = re.search(r"in (\d+) internal steps", m)
            self.steps += int(hit.group(1)) if hit and cat == "logEvents" else 0
        self.seen = len(self.s.messages)
        self.sample(force, x_old)
        return True

    def run(self, n, h, garbage=None):
        """n steps of h, stopping at an error; with `garbage` (a relative energy drift) the first
        OK point whose constraint errors or energy balance are out of bounds is remembered."""
        for _ in range(n):
            if not self.step(h):
                return False
            o = self.last
            bad = not self.finite or o[0] > 1e-12 or o[1] > self.orth_floor or self.drift() > (garbage or math.inf)
            if garbage is not None and self.first_bad is None and bad:
                self.first_bad = (self.s.time, *self.last[:3])
        return True


def base_checks(tr):
    return {"finite outputs": tr.finite, f"no doStep error ({tr.error})": tr.error is None,
            f"constraint errors <= 1e-12 (got {tr.max_err[0]:.2e} m, {tr.max_err[1]:.2e} m^2/s)":
                bool(tr.max_err[0] <= 1e-12 and tr.max_err[1] <= tr.orth_floor)}


def names_fix(msg):
    cause = any(w in msg.lower() for w in ("stab", "stiff", "frequen", "non-finite", "step size", "step_size"))
    return cause and any(w in msg for w in ("solver.step_size", "step size", "dopri5"))


def refusal_checks(tr, snap, at_snap, drift_bound):
    """A run that cannot be met must end in an error/discard naming cause and fix with the last
    good state kept, never return NaN or a finite but exploding state with fmi2OK."""
    checks = {}
    if tr.first_bad:
        t, le, oe, E = tr.first_bad
        checks[f"doStep returned OK with garbage at t = {t:.4g} s: length error {le:.2e} m, orthogonality "
               f"{oe:.2e} m^2/s, energy.total {E:.3e} J (at start {tr.E0:.3e} J), all finite={tr.finite}"] = False
    if tr.error:
        checks[f"error names cause and fix: {tr.error[1]!r}"] = names_fix(tr.error[1])
        checks["state kept at the last good point"] = bool(tr.intact)
    else:
        checks.update(base_checks(tr))
        checks[f"energy balance {tr.drift():.1e} <= {drift_bound}"] = tr.drift() <= drift_bound
    tr.s.fmu.setFMUstate(snap)
    checks["setFMUstate restores the snapshot"] = bool(np.array_equal(tr.s.outputs(), at_snap))
    tr.s.fmu.freeFMUstate(snap)
    return checks


def stiffness(f, kappa):
    return {f"cable[{j}].stiffness": kappa for j in range(1, 100) if f"cable[{j}].stiffness" in f.vr}


# ------------------------------------------------------------------ 1. stiff cables
@pytest.mark.parametrize("kappa", [1e5, 1e6, 1e7], ids=["1e5", "1e6", "1e7"])
def test_stiff_cables(fmus, open_fmu, kappa):
    """prism2-elastic, every cable at kappa (prestress rest lengths kept: the self-stress scales),
    100 N on node[7].fx, dopri5 1e-9: 1 ms vs 0.1 ms communication steps over 1 s."""
    f = fmus.builtin("prism2-elastic")
    load, runs = {"node[7].fx": 100.0}, []
    for comm in (1e-3, 1e-4):
        tr, pos = Tracker(start(open_fmu, f, "dopri5", stiffness(f, kappa), load, name=f"c{comm}")), []
        for k in range(1000):
            tr.run(round(1e-3 / comm), comm)
            pos.append(tr.last[3:3 + len(tr.P)])
        runs.append((tr, np.array(pos)))
    (tr, p1), (tr2, p2) = runs
    diff = float(np.abs(p1 - p2).max())
    checks = {**base_checks(tr), **base_checks(tr2), f"energy balance {tr.drift():.1e} <= 1e-6": tr.drift() <= 1e-6,
              f"1 ms vs 0.1 ms communication: {diff:.2e} <= 1e-6 m": diff <= 1e-6}
    tr.max_err = np.maximum(tr.max_err, tr2.max_err)
    failed = record(f"stiff_cables_{kappa:.0e}", "dopri5", tr.steps, tr, checks,
                    f"prism2-elastic, all cables {kappa:.0e} N/m, 100 N on node[7].fx, rtol=atol=1e-9, 1 s; steps = "
                    f"accepted internal dopri5 steps (logEvents) at 1 ms communication ({tr2.steps} at 0.1 ms); "
                    f"max node-position diff 1 ms vs 0.1 ms = {diff:.2e} m")
    if kappa == 1e7:  # rk4 at 1 ms is beyond its stability limit (h w ~ 8): it must refuse
        s = start(open_fmu, f, "rk4", stiffness(f, kappa), load, name="rk4")
        tr, snap, at_snap = Tracker(s), s.fmu.getFMUstate(), s.outputs()
        tr.run(1000, 1e-3, garbage=1e-3)
        checks = refusal_checks(tr, snap, at_snap, 1e-3)
        failed += record("stiff_cables_1e+07", "rk4", tr.steps, tr, checks,
                         f"rk4 at 1 ms: {'error at t = %.4g s: %s' % tr.error if tr.error else 'no error'}; "
                         f"{tr.steps} steps accepted before it", rejected=tr.error is not None)
    verdict(failed)


# ------------------------------------------------------------------ 2. long horizon
def icosahedron_ringing(open_fmu, fmus, method, correction=True):
    """Icosahedron: 5 N / -3 N on nodes 4 and 8 for 0.1 s, then free (1e6 steps of 1 ms in all)."""
    s = start(open_fmu, fmus.builtin("icosahedron"), method, inputs={"node[4].fx": 5.0, "node[8].fy": -3.0},
              correction=correction, name=method)
    tr = Tracker(s)
    tr.run(100, 1e-3)
    s.set({"node[4].fx": 0.0, "node[8].fy": 0.0})
    return tr


@pytest.mark.parametrize("method", ["rk4", "rattle"])
def test_long_horizon_icosahedron(fmus, open_fmu, method):
    tr = icosahedron_ringing(open_fmu, fmus, method)
    tr.run(9999, 0.1)
    checks = {**base_checks(tr), f"1e6 steps done ({tr.steps})": tr.steps == 1_000_000,
              f"energy drift {tr.drift():.2e} <= 1e-3": tr.drift() <= 1e-3}
    verdict(record("long_horizon_icosahedron", method, tr.steps, tr, checks,
                   "icosahedron rung by 0.1 s of load, then free; 1 ms internal steps for 1000 s; checked every 0.1 s"))


# ------------------------------------------------------------------ 3. slack and taut
def shaken(open_fmu, f, method, params):
    tr = Tracker(start(open_fmu, f, method, params, name=method), keep=True,
                 extra=[f"cable[{j}].tension" for j in range(1, 16)])
    for k in range(1000):
        t, A = k * 1e-3, 40.0
        tr.s.set({"node[7].fz": A * math.sin(6 * math.pi * t), "node[8].fx": A * math.cos(4 * math.pi * t),
                  "node[9].fy": -A * math.sin(10 * math.pi * t)})
        tr.step(1e-3)
    hist = np.array(tr.hist)
    return tr, hist[:, 3:3 + len(tr.P)], hist[:, -15:]


def test_slack_and_taut(fmus, open_fmu):
    f = fmus.builtin("prism2-elastic")
    _, ref, _ = shaken(open_fmu, f, "dopri5", {"solver.rtol": 1e-12, "solver.atol": 1e-12})
    sweeps = {"rk4": [{"solver.step_size": h} for h in (1e-3, 5e-4, 2.5e-4)],
              "rattle": [{"solver.step_size": h} for h in (1e-3, 5e-4, 2.5e-4)],
              "dopri5": [{"solver.rtol": t, "solver.atol": t} for t in (1e-6, 1e-8, 1e-10)]}
    failed = []
    for method, sweep in sweeps.items():
        errs, checks, flips, tmin, trs = [], {}, [], [], []
        for p in sweep:
            tr, pos, ten = shaken(open_fmu, f, method, p)
            slack = ten <= 0.0
            flips.append(int(np.sum(slack[1:] != slack[:-1])))
            tmin.append(float(ten.min()))
            errs.append(float(np.abs(pos - ref).max()))
            checks.update(base_checks(tr))
            trs.append(tr)
        tr0 = trs[0]
        ratios = [a / b for a, b in zip(errs, errs[1:])]
        if method == "dopri5":
            # Its switches located, dopri5 meets each tolerance: measured 3.7e-8, 3.5e-8 and
            # 3.2e-9 m at 1e-6, 1e-8 and 1e-10, so the first refinement gains little.
            tols = [p["solver.rtol"] for p in sweep]
            converges = {f"error within 100x its tolerance and the tightest 5x below the loosest "
                         f"(errors {[f'{e:.2e}' for e in errs]})":
                             all(e <= 100 * t for e, t in zip(errs, tols)) and errs[-1] * 5 <= errs[0]}
        else:
            converges = {f"converges as the step shrinks (error ratios {[round(r, 2) for r in ratios]} >= 1.5)":
                             all(r >= 1.5 for r in ratios)}
        checks.update({f"tensions never negative (min {min(tmin)})": min(tmin) >= 0.0,
                       f"cables go slack and taut repeatedly ({flips[0]} transitions >= 20)": flips[0] >= 20,
                       **converges})
        orders = f"; observed orders {[round(math.log2(r), 2) for r in ratios]}" if method != "dopri5" else ""
        at = "tol = 1e-6, 1e-8, 1e-10" if method == "dopri5" else "h = 1, 0.5, 0.25 ms"
        failed += record("slack_and_taut", method, tr0.steps, tr0, checks,
                         f"prism2-elastic, 40 N loads at 3, 2, 5 Hz on nodes 7-9, 1 s, {flips[0]} slack/taut "
                         f"transitions; steps of the first run; max position error vs dopri5 1e-12 at {at}: "
                         f"{', '.join('%.2e' % e for e in errs)} m{orders}")
    verdict(failed)


# ------------------------------------------------------------------ 4. big communication steps
@pytest.mark.parametrize("method", ["rk4", "rattle"])
def test_big_communication_steps(fmus, open_fmu, method):
    f = fmus.builtin("prism2-elastic")
    fine, one, ten = (Tracker(start(open_fmu, f, method, inputs={"node[7].fx": 10.0, "node[9].fz": -5.0}, name=n))
                      for n in ("fine", "one", "ten"))
    d1 = 0.0
    for _ in range(10):
        fine.run(1000, 1e-3)
        one.run(1, 1.0)
        d1 = max(d1, float(np.abs(one.last - fine.last).max()))
    ten.run(1, 10.0)
    d10 = float(np.abs(ten.last - fine.last).max())
    same = np.array_equal(ten.last, fine.last) and np.array_equal(one.last, fine.last)
    checks = {**base_checks(fine), **base_checks(one), **base_checks(ten),
              f"1 s steps vs 1 ms steps {d1:.1e} <= 1e-12": d1 <= 1e-12,
              f"10 s step vs 1 ms steps {d10:.1e} <= 1e-12": d10 <= 1e-12,
              f"1e4 internal steps each ({fine.steps}, {one.steps}, {ten.steps})":
                  fine.steps == one.steps == ten.steps == 10000}
    verdict(record("big_communication_steps", method, ten.steps, fine, checks,
                   f"prism2-elastic, constant load, 10 s of 1 ms internal steps; all outputs compared every second; "
                   f"bit-identical: {same}"))


# ------------------------------------------------------------------ 5. class-k, many joints
def toml(name, nodes, bars, cables, fixed=(), inputs=(), gravity=None, velocities=None, extra=""):
    fl = lambda rows: [[float(x) for x in r] for r in rows]
    t = f'name = "{name}"\nnodes = {fl(nodes)}\nfixed = {list(fixed)}\nforce_inputs = {list(inputs)}\n' + extra
    t += f"gravity = {list(map(float, gravity))}\n" if gravity else ""
    t += f"velocities = {fl(velocities)}\n" if velocities else ""
    t += "".join(f"\n[[bars]]\nnodes = [{a}, {b}]\nmass = 1.0\n" for a, b in bars)
    return t + "".join(f"\n[[cables]]\nnodes = [{c[0]}, {c[1]}]\nstiffness = {c[2]!r}\n"
                       + (f"rest_length = {c[3]!r}\n" if len(c) > 3 else "") for c in cables)


def tower(stages):
    """The built-in tower formula (src/scene/builtin.rs) for any number of stages."""
    r, h, nid = 1 / math.sqrt(3), 0.5 + math.sqrt(3) / 6, lambda ring, i: 3 * ring + i + 1
    ang = lambda ring, i: math.radians(ring * 150 + i * 120)
    nodes = [[r * math.cos(ang(g, i)), r * math.sin(ang(g, i)), g * h]
             for g in range(stages + 1) for i in range(3)]
    bars = [(nid(k, i), nid(k + 1, i)) for k in range(stages) for i in range(3)]
    cables = [(nid(g, i), nid(g, (i + 1) % 3), 500.0) for g in range(stages + 1) for i in range(3)]
    cables += [(nid(k, i), nid(k + 1, (i + 2) % 3), 500.0) for k in range(stages) for i in range(3)]
    return toml(f"tower{stages}", nodes, bars, cables, [1, 2, 3], [nid(stages, i) for i in range(3)],
                extra="prestress = { min_tension = 10.0 }\n")


def tripod():
    """Free apex node 1 shared by 3 bars; the feet tied by slack-free elastic cables."""
    feet = [(0.8 * math.cos(a), 0.8 * math.sin(a), 0.0) for a in (0, 2 * math.pi / 3, 4 * math.pi / 3)]
    side = math.dist(feet[0], feet[1])
    return toml("tripod", [(0, 0, 1.0)] + feet, [(1, 2), (1, 3), (1, 4)],
                [(2, 3, 500.0, side), (3, 4, 500.0, side), (4, 2, 500.0, side)], inputs=[1])


@pytest.mark.parametrize("case", ["tower20", "tower100", "tripod"])
def test_class_k_many_joints(fmus, open_fmu, case):
    f = fmus.builtin("tower20") if case == "tower20" else fmus.from_toml(tower(100) if case == "tower100" else tripod())
    top = f.scene["force_inputs"][0]
    tr = Tracker(start(open_fmu, f, "rk4", inputs={f"node[{top}].fx": 20.0, f"node[{top}].fz": -10.0}))
    tr.run(1000, 1e-3)
    checks = {**base_checks(tr), f"energy balance {tr.drift():.1e} <= 1e-6": tr.drift() <= 1e-6}
    note = f"{case}: {len(f.scene['bars'])} bars, 20 N x / -10 N z on node {top}, rk4 1 ms, 1 s"
    if case == "tripod":  # free: momentum = impulse of the load
        _, v = tr.xv(tr.last)
        p = sum(m / 2 * (v[a] + v[b]) for a, b, m in tr.bars)
        dp = float(np.abs(p - np.array([20.0, 0, -10.0]) * tr.s.time).max())
        checks[f"linear momentum = load impulse ({dp:.1e} <= 1e-9 N s)"] = dp <= 1e-9
        note += "; free tripod, node 1 shared by 3 bars"
    verdict(record(f"class_k_{case}", "rk4", tr.steps, tr, checks, note))


# ------------------------------------------------------------------ 6. near-degenerate geometry
def degenerate(kind):
    g = (0.0, 0.0, -9.81)
    if kind == "collinear":  # bars 1-2 and 2-3 at 1e-6 rad from straight, compressed by cable 1-3
        n = [(0, 0, 0), (1, 0, 0), (2, 1e-6, 0), (2, 0.5, 0)]
        cables = [(1, 3, 500.0, 0.999 * math.dist(n[0], n[2])), (3, 4, 500.0, 0.5)]
        return toml(kind, n, [(1, 2), (2, 3)], cables, [1, 4], gravity=g)
    n = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0.2)]
    pinned = toml("pinned-bar", n, [(1, 2), (3, 4)], [(2, 4, 500.0, 1.0)], [1, 2, 3], gravity=g)
    if kind == "pinned_bar":  # bar 1 has both ends pinned: its correction direction vanishes
        return pinned
    if kind == "redundant_pins":  # fixed = [1, 1, 2, 3]: node 1 pinned twice, P rank deficient
        return pinned.replace("fixed = [1, 2, 3]", "fixed = [1, 1, 2, 3]").replace("pinned-bar", "redundant")
    d = 1e-6  # a 1 micrometre cable between two pendulums
    n = [(0, 0, 0), (1, 0, 0), (1 + d, 0, 0), (2, 0.3, 0)]
    return toml("short-cable", n, [(1, 2), (3, 4)], [(2, 3, 500.0, d / 2)], [1, 4], gravity=g)


@pytest.mark.parametrize("kind", ["collinear", "pinned_bar", "redundant_pins", "short_cable"])
def test_near_degenerate(fmus, open_fmu, kind):
    try:
        f = fmus.from_toml(degenerate(kind))
    except subprocess.CalledProcessError as e:
        msg, ok = e.stderr.strip(), bool(re.search(r"(fixed|bars|cables|nodes)(\[\d+\])?", e.stderr))
        verdict(record(f"near_degenerate_{kind}", "-", 0, None,
                       {f"build rejected with a clear message naming the key: {msg!r}": ok}, msg, rejected=True))
        return
    failed = []
    for method in ("rk4", "dopri5"):
        tr = Tracker(start(open_fmu, f, method, name=method))
        tr.run(1000, 1e-3)
        checks = {**base_checks(tr), f"energy balance {tr.drift():.1e} <= 1e-3": tr.drift() <= 1e-3}
        if kind in ("pinned_bar", "redundant_pins"):
            x = np.array(tr.s.get(tr.P[:9]))
            checks["pinned nodes 1-3 never move"] = bool(np.array_equal(x, np.ravel(f.scene["nodes"][:3])))
        if kind == "redundant_pins":
            ref = Tracker(start(open_fmu, fmus.from_toml(degenerate("pinned_bar")), method, name="ref" + method))
            ref.run(1000, 1e-3)
            d = float(np.abs(ref.last - tr.last).max())
            checks[f"same motion as without the duplicate pin ({d:.1e} <= 1e-12)"] = d <= 1e-12
        failed += record(f"near_degenerate_{kind}", method, tr.steps, tr, checks,
                         f"{kind} under gravity, 1 s at 1 ms; warnings: {tr.s.warnings()}")
    verdict(failed)


# ------------------------------------------------------------------ 7. fast spin
@pytest.mark.parametrize("method", ["rk4", "dopri5", "rattle"])
def test_fast_spin(fmus, open_fmu, method):
    f = fmus.from_toml(toml("spin", [(0.5, 0, 0), (-0.5, 0, 0)], [(1, 2)], [], velocities=[(0, 50, 0), (0, -50, 0)]))
    s = start(open_fmu, f, method, {"solver.rtol": 1e-10, "solver.atol": 1e-10})
    tr = Tracker(s, keep=True, extra=["bar[1].force"])
    tr.run(1000, 1e-3)
    h = np.array(tr.hist)
    x, v = h[:, 3:9], h[:, 9:15]
    w = np.cross(x[:, :3] - x[:, 3:], v[:, :3] - v[:, 3:])[:, 2]  # |d| = 1 m
    dw = float(np.abs(w / 100 - 1).max())
    dx = float(np.abs(x[-1, :3] - [0.5 * math.cos(100), 0.5 * math.sin(100), 0.0]).max())
    df = float(np.abs(h[:, -1] / (-100 ** 2 / 12) - 1).max())
    checks = {**base_checks(tr), f"angular velocity 100 rad/s kept (rel. {dw:.1e} <= 1e-4)": dw <= 1e-4,
              f"energy drift {tr.drift():.1e} <= 1e-4": tr.drift() <= 1e-4,
              f"bar force = centrifugal -m w^2 L/12 of the two-node bar (rel. {df:.1e} <= 1e-4)": df <= 1e-4,
              f"end position vs exact rotation {dx:.1e} <= 1e-3 m": dx <= 1e-3}
    if method == "rattle":
        # A second-order method's phase error at w h = 0.1 is O(h^2), not 1e-3 m: check
        # instead that it shrinks fourfold when the step halves.
        half = Tracker(start(open_fmu, f, method, {"solver.step_size": 5e-4}), keep=True)
        half.run(2000, 5e-4)
        dx2 = float(np.abs(np.array(half.hist)[-1, 3:6] - [0.5 * math.cos(100), 0.5 * math.sin(100), 0.0]).max())
        del checks[f"end position vs exact rotation {dx:.1e} <= 1e-3 m"]
        checks[f"phase error {dx:.1e} -> {dx2:.1e} m when h halves (ratio 3..5)"] = 3 <= dx / dx2 <= 5
    verdict(record("fast_spin", method, tr.steps, tr, checks,
                   f"free 1 m, 1 kg bar at 100 rad/s (scene velocities), 1 s at 1 ms; w(1 s) = {w[-1]:.5f} rad/s"))


# ------------------------------------------------------------------ 8. free-floating structure
@pytest.mark.parametrize("method", ["rk4", "dopri5", "rattle"])
def test_free_floating(fmus, open_fmu, method):
    vel = np.random.default_rng(5).normal(scale=0.3, size=(12, 3)).tolist()
    text = fmus.builtin("icosahedron").scene_text.replace("fixed = [1, 5, 9]", "fixed = []").replace(
        "force_inputs = [4, 8, 12]", f"force_inputs = []\nvelocities = {vel}").replace('"icosahedron"', '"ico-free"')
    tr = Tracker(start(open_fmu, fmus.from_toml(text), method), keep=True)
    tr.run(2000, 1e-3)
    h = np.array(tr.hist)
    x, v = h[:, 3:39].reshape(-1, 12, 3), h[:, 39:75].reshape(-1, 12, 3)
    p = sum(m / 2 * (v[:, a] + v[:, b]) for a, b, m in tr.bars)
    ang = sum(m * ((np.cross(x[:, a], v[:, a]) + np.cross(x[:, b], v[:, b])) / 3
                   + (np.cross(x[:, a], v[:, b]) + np.cross(x[:, b], v[:, a])) / 6) for a, b, m in tr.bars)
    com = sum(m / 2 * (x[:, a] + x[:, b]) for a, b, m in tr.bars) / tr.mass
    dp = float(np.abs(p - p[0]).max())
    dl = float(np.abs(ang - ang[0]).max() / np.abs(ang[0]).max())
    dc = float(np.abs(com - com[0] - p[0] / tr.mass * (np.arange(len(h))[:, None] * 1e-3)).max())
    checks = {**base_checks(tr), f"linear momentum kept ({dp:.1e} <= 1e-12 N s)": dp <= 1e-12,
              f"angular momentum kept (rel. {dl:.1e} <= 1e-8)": dl <= 1e-8,
              f"centre of mass moves uniformly ({dc:.1e} <= 1e-10 m)": dc <= 1e-10}
    verdict(record("free_floating", method, tr.steps, tr, checks,
                   "icosahedron without pins or gravity, random start velocities (projected), 2 s at 1 ms"))


# ------------------------------------------------------------------ 9. hostile inputs
@pytest.mark.parametrize("kind", ["huge_dopri5", "huge_rk4", "negative", "nonfinite"])
def test_hostile_inputs(fmus, open_fmu, kind):
    f = fmus.builtin("prism2")
    method = "dopri5" if kind == "huge_dopri5" else "rk4"
    s = start(open_fmu, f, method)
    s.run(10, 1e-3)
    snap, at_snap, rejected = s.fmu.getFMUstate(), s.outputs(), False
    if kind.startswith("huge"):
        s.set({"cable[14].force_density": 1e9})
        tr = Tracker(s)
        tr.run(20, 1e-3, garbage=1e-4)
        checks, rejected = refusal_checks(tr, snap, at_snap, 1e-4), tr.error is not None
        s.time = 0.01
        s.run(5, 1e-3)
        checks["runs on finitely after setFMUstate"] = bool(np.all(np.isfinite(s.outputs())))
        note = (f"cable[14].force_density = 1e9 N/m at t = 10 ms, then 20 ms at 1 ms communication; "
                f"{'error: ' + tr.error[1] if tr.error else 'simulated'}; steps = internal steps after the change"
                + (f"; orthogonality bound max(1e-12, 16 eps |v|max L) = {tr.orth_floor:.1e} m^2/s (|v| ~ 1e4 m/s)"
                   if tr.orth_floor > 1e-12 else ""))
    elif kind == "negative":
        vr = (ctypes.c_uint * 1)(*s.vrs(["cable[7].force_density"]))
        st = s.fmu.fmi2SetReal(s.fmu.component, vr, 1, (ctypes.c_double * 1)(-50.0))
        tr = Tracker(s, keep=True, extra=[f"cable[{j}].tension" for j in range(1, 16)])
        tr.run(500, 1e-3)
        ten = np.array(tr.hist)[:, -15:]
        checks = {**base_checks(tr), f"fmi2SetReal returns fmi2Warning (got {st})": st == 1,
                  "warning names cable[7].force_density": any("cable[7].force_density" in m for m in s.warnings()),
                  "cable[7] tension clamped to 0 throughout": bool(np.all(ten[:, 6] == 0.0)),
                  "no negative tension": bool(ten.min() >= 0.0)}
        note = f"cable[7].force_density = -50 N/m at 10 ms, 0.5 s more; warning: {s.warnings()}"
        s.fmu.freeFMUstate(snap)
    else:
        checks = {}
        for name, bad in (("cable[7].force_density", math.nan), ("node[7].fx", math.inf), ("node[8].fz", -math.inf)):
            s.fmu.setFMUstate(snap)
            try:
                s.set({name: bad})
                raised = False
            except FMICallException:
                raised = True
            err = (s.errors() or [""])[-1]
            checks[f"{name} = {bad}: fmi2Error"] = raised
            checks[f"{name} = {bad}: message names it and 'finite' ({err!r})"] = name in err and "finite" in err
            checks[f"{name} = {bad}: outputs unchanged"] = bool(np.array_equal(s.outputs(), at_snap))
        s.fmu.setFMUstate(snap)
        s.fmu.freeFMUstate(snap)
        s.time, tr = 0.01, Tracker(s)
        tr.run(20, 1e-3)
        ref = start(open_fmu, f, method, name="ref")
        ref.run(30, 1e-3)
        checks.update(base_checks(tr))
        checks["after setFMUstate the run equals an undisturbed one bit for bit"] = bool(
            np.array_equal(s.outputs(), ref.outputs()))
        rejected, note = True, "NaN / inf / -inf inputs at 10 ms, each rejected; setFMUstate, then 20 ms more"
    verdict(record(f"hostile_inputs_{kind.split('_')[0]}", method, tr.steps, tr, checks, note, rejected=rejected))


# ------------------------------------------------------------------ 10. without correction
@pytest.mark.parametrize("case", ["stiff_dopri5", "long_rk4", "long_rattle"])
def test_without_correction(fmus, open_fmu, case):
    if case == "stiff_dopri5":
        f = fmus.builtin("prism2-elastic")
        tr, on = (Tracker(start(open_fmu, f, "dopri5", stiffness(f, 1e7), {"node[7].fx": 100.0},
                                correction=c, name=str(c))) for c in (False, True))
        on.run(1000, 1e-3)
        n, h, bound = 1000, 1e-3, on.max_err[0]
    else:
        tr = icosahedron_ringing(open_fmu, fmus, case[5:], correction=False)
        n, h, bound = 9999, 0.1, 1e-12
    tr.run(n, h)
    lmin = min(math.dist(tr.s.file.scene["nodes"][a], tr.s.file.scene["nodes"][b]) for a, b, _ in tr.bars)
    checks = {"finite outputs": tr.finite,
              f"drift shows: max length error {tr.max_err[0]:.2e} > with correction {bound:.1e}": tr.max_err[0] > bound,
              # Without the correction the energy may drift (that is the point of the case);
              # what must not happen is a state whose bars are no longer bars returned as OK.
              f"no destroyed state returned with fmi2OK (length error {tr.max_err[0]:.1e} <= 1% of a bar)":
                  tr.max_err[0] <= 0.01 * lmin}
    if tr.error:
        checks[f"error names cause and fix: {tr.error[1]!r}"] = names_fix(tr.error[1])
    when = (f"length error first > 1e-6 m at t = {tr.t_hit:.4g} s" if tr.t_hit
            else f"never > 1e-6 m (max {tr.max_err[0]:.2e} m)")
    kind, method = case.split("_")
    verdict(record("without_correction", f"{method} ({kind})", tr.steps, tr, checks,
                   f"correction off; {when}; ran to t = {tr.s.time:.4g} s"
                   + (f"; stopped by error: {tr.error[1]}" if tr.error else "")))


# ------------------------------------------------------------------ found: order under changing inputs
@pytest.mark.parametrize("method", ["rk4", "rattle"])
def test_changing_inputs_keep_the_order(fmus, open_fmu, method):
    """A smooth load (5 +- 5 N at 3 Hz, set before every 1 ms doStep) must not lower a fixed-step
    method's convergence order below the one it shows under a constant load."""
    f = fmus.builtin("prism2-elastic")

    def final(m, params, vary):
        tr = Tracker(start(open_fmu, f, m, params, {"node[7].fz": 5.0}, name=m))
        for k in range(500):
            if vary:
                tr.s.set({"node[7].fz": 5.0 + 5.0 * math.sin(6 * math.pi * k * 1e-3)})
            tr.step(1e-3)
        return tr, tr.last[3:3 + len(tr.P)]

    orders = {}
    for vary in (False, True):
        _, ref = final("dopri5", {"solver.rtol": 1e-13, "solver.atol": 1e-13}, vary)
        runs = [final(method, {"solver.step_size": h}, vary) for h in (1e-3, 5e-4, 2.5e-4)]
        errs = [float(np.abs(x - ref).max()) for _, x in runs]
        orders[vary] = ([round(math.log2(a / b), 2) for a, b in zip(errs, errs[1:])], errs)
        tr = runs[0][0]
    want = 3.5 if method == "rk4" else 1.7
    checks = {**base_checks(tr), **{f"{'changing' if v else 'constant'} load: order {o[0]} >= {want}": min(o[0]) >= want
                                    for v, o in orders.items()}}
    verdict(record("changing_inputs_order", method, tr.steps, tr, checks,
                   "prism2-elastic, 0.5 s, errors vs dopri5 1e-13 at h = 1, 0.5, 0.25 ms: constant load "
                   + ", ".join("%.2e" % e for e in orders[False][1]) + " m; changing load "
                   + ", ".join("%.2e" % e for e in orders[True][1]) + " m"))
