"""A tensegrity scene as a MuJoCo model (MJCF written from the scene, nothing by hand).

The mapping keeps the project's mechanics (`shared/design/dynamics.md`):
- each bar is a free body with the bar's mass at its centre and a thin uniform rod's
  inertia `m L²/12` about its centre (payloads of `[[point_masses]]` are added at the bar
  end the project puts them on: the first bar end listed at their node);
- bar ends at a shared node are joined by `connect` equalities, pinned ends are connected
  to a world site at the pin (or, with `joints="tree"`, the bars hang on ball joints along
  a spanning tree grown from the pins, and equalities close only the loops);
- elastic cables are spatial tendons between the node sites, stiffness κ and
  `springlength="0 L"`: no force below the rest length L, so a cable goes slack;
- force inputs are actuators at the node sites whose gear is in a world-fixed frame, so
  a constant control is a constant force in world axes, as `node[i].fx/fy/fz` is;
- gravity is the scene's (none when it declares none); contacts are disabled.

What differs is MuJoCo's own: its equality constraints are soft (solref/solimp), so the
joints give a little under load where the project's are exact; ball joints are exact.
"""

from dataclasses import dataclass
from xml.sax.saxutils import quoteattr

import mujoco
import numpy as np

# The world-fixed frame whose axes the force actuators push along.
WORLD_FRAME_SITE = "world_frame"
# A bar's spin about its own axis is never excited (every force acts on the axis and the
# rod is axisymmetric), so any positive axial inertia gives the same motion; MuJoCo needs
# one. This fraction of the transverse inertia keeps the mass matrix well conditioned.
AXIAL_INERTIA_FRACTION = 1e-3


@dataclass(frozen=True)
class MujocoSettings:
    """MuJoCo's numerical settings; the defaults are the ones the benchmark uses."""

    timestep: float = 1e-3
    integrator: str = "implicitfast"  # or "RK4", "Euler", "implicit"
    # "equality": every bar a free body, joints as connect equalities (as a general
    # tensegrity needs); "tree": ball joints along a spanning tree of the bars, equalities
    # only where bars close a loop (none in a tower).
    joints: str = "equality"
    # Equality softness: impedance d = 0.9999 (MuJoCo's largest) makes a joint carry all
    # but 1e-4 of the load that would pull it apart; the time constant (0.002 s: the
    # smallest MuJoCo accepts at a 1 ms step, 2 steps) sets how fast the remaining
    # violation is pulled back. The give goes as (1 − d) τ².
    solref: tuple = (0.002, 1.0)
    solimp: tuple = (0.9999, 0.9999, 0.001, 0.5, 2.0)
    solver: str = "Newton"
    iterations: int = 100
    tolerance: float = 1e-12


@dataclass(frozen=True)
class Structure:
    """What the MJCF is written from: the scene's topology and geometry (its TOML, as the
    FMU ships it) and the FMU's parameter values (rest lengths derived from the prestress,
    stiffnesses, masses, gravity)."""

    scene: dict
    parameters: dict

    @property
    def nodes(self) -> np.ndarray:
        return np.asarray(self.scene["nodes"], dtype=float)

    @property
    def bars(self) -> list:
        return [tuple(b["nodes"]) for b in self.scene["bars"]]

    @property
    def pinned(self) -> set:
        return set(self.scene.get("fixed", []))

    def bar_mass(self, k: int) -> float:
        return self.parameters.get(f"bar[{k}].mass", self.scene["bars"][k - 1]["mass"])

    def gravity(self) -> np.ndarray:
        if "gravity" not in self.scene:
            return np.zeros(3)
        return np.array([self.parameters[f"gravity.{a}"] for a in "xyz"])

    def cable_law(self, j: int) -> tuple:
        """(stiffness N/m, rest length m) of elastic cable j, 1-based."""
        return self.parameters[f"cable[{j}].stiffness"], self.parameters[f"cable[{j}].rest_length"]

    def total_mass(self) -> float:
        bars = sum(self.bar_mass(k) for k in range(1, len(self.bars) + 1))
        return bars + sum(p["mass"] for p in self.scene.get("point_masses", []))


def check_supported(structure: Structure):
    """Refuses scene features this mapping does not carry over, naming them."""
    scene = structure.scene
    for j, cable in enumerate(scene["cables"], start=1):
        if cable.get("control") or cable.get("damping"):
            raise NotImplementedError(
                f"cables[{j}]: only undamped elastic cables are mapped to MuJoCo"
            )
    for key in ("loads", "ground", "velocities"):
        if scene.get(key):
            raise NotImplementedError(f"scene key {key!r} is not mapped to MuJoCo")
    if scene.get("start", "as_given") != "as_given":
        raise NotImplementedError("only start = \"as_given\" is mapped to MuJoCo")


def bar_site(k: int, side: int) -> str:
    """Site at end `side` (0 = first node, 1 = second) of bar k (1-based)."""
    return f"bar{k}.{'ab'[side]}"


def node_sites(structure: Structure) -> list:
    """The site standing for each node: the first bar end listed there (the end the project
    reads the node from), or a world site for a node on no bar."""
    sites = [f"node{i}" for i in range(1, len(structure.nodes) + 1)]
    seen = set()
    for k, bar in enumerate(structure.bars, start=1):
        for side, node in enumerate(bar):
            if node not in seen:
                seen.add(node)
                sites[node - 1] = bar_site(k, side)
    return sites


def _vec(v) -> str:
    return " ".join(repr(float(x)) for x in v)


def _bar_frame(structure: Structure, k: int):
    """(centre, rotation whose z column runs from the bar's first node to its second, length)."""
    a, b = structure.bars[k - 1]
    pa, pb = structure.nodes[a - 1], structure.nodes[b - 1]
    z = (pb - pa) / np.linalg.norm(pb - pa)
    helper = np.eye(3)[np.argmin(np.abs(z))]
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return (pa + pb) / 2, np.column_stack([x, np.cross(z, x), z]), float(np.linalg.norm(pb - pa))


def _quat(rotation: np.ndarray) -> np.ndarray:
    q = np.empty(4)
    mujoco.mju_mat2Quat(q, rotation.flatten())
    return q


@dataclass
class Plan:
    """How the bars become bodies: each bar's parent (0 = the world) and joint ("free",
    "ball" at one end, or None: welded, for a bar pinned at both ends), and the connect
    equalities (site, site) for every bar end the joints leave unjoined."""

    parent: dict
    joint: dict
    joint_side: dict
    connects: list


def _ends_at(structure: Structure) -> dict:
    ends = {}
    for k, bar in enumerate(structure.bars, start=1):
        for side, node in enumerate(bar):
            ends.setdefault(node, []).append((k, side))
    return ends


def _is_static(structure: Structure, k: int) -> bool:
    return set(structure.bars[k - 1]) <= structure.pinned


def equality_plan(structure: Structure) -> Plan:
    """Every bar a free body; joints and pins are all connect equalities."""
    bars = range(1, len(structure.bars) + 1)
    plan = Plan({k: 0 for k in bars}, {}, {}, [])
    for k in bars:
        plan.joint[k] = None if _is_static(structure, k) else "free"
    for node, ends in sorted(_ends_at(structure).items()):
        moving = [e for e in ends if not _is_static(structure, e[0])]
        if node in structure.pinned:
            plan.connects += [(bar_site(*e), f"node{node}") for e in moving]
        else:
            plan.connects += [(bar_site(*e), bar_site(*ends[0])) for e in ends[1:]]
    return plan


def tree_plan(structure: Structure) -> Plan:
    """Bars as a kinematic tree of ball joints grown from the pins (a free root for a
    component without one); connect equalities only where the bars close a loop."""
    ends_at = _ends_at(structure)
    plan = Plan({}, {}, {}, [])
    queue = []
    for k, bar in enumerate(structure.bars, start=1):
        pinned_sides = [side for side, node in enumerate(bar) if node in structure.pinned]
        if pinned_sides:
            plan.parent[k] = 0
            plan.joint[k] = None if len(pinned_sides) == 2 else "ball"
            plan.joint_side[k] = pinned_sides[0]
            queue.append(k)
    anchor = {}  # node -> the bar end the others at that node are joined to
    bars = list(range(1, len(structure.bars) + 1))
    while len(plan.parent) < len(bars) or queue:
        if not queue:  # a component with no pin: its first bar floats freely
            root = next(k for k in bars if k not in plan.parent)
            plan.parent[root], plan.joint[root] = 0, "free"
            queue.append(root)
        k = queue.pop(0)
        for side, node in enumerate(structure.bars[k - 1]):
            if node in structure.pinned or node in anchor:
                continue
            anchor[node] = (k, side)
            for child, child_side in ends_at[node]:
                if child not in plan.parent:
                    plan.parent[child], plan.joint[child] = k, "ball"
                    plan.joint_side[child] = child_side
                    queue.append(child)
    for node, ends in sorted(ends_at.items()):
        for k, side in ends:
            if _joined_by_tree(plan, structure, node, (k, side), anchor.get(node)):
                continue
            target = f"node{node}" if node in structure.pinned else bar_site(*anchor[node])
            plan.connects.append((bar_site(k, side), target))
    return plan


def _joined_by_tree(plan: Plan, structure: Structure, node: int, end: tuple, anchor) -> bool:
    """Whether the tree already holds this bar end at its node: it is the node's anchor, its
    bar is welded, or its ball joint sits there on the anchor's bar (on the world at a pin)."""
    k, side = end
    if end == anchor or plan.joint[k] is None:
        return True
    at_its_joint = plan.joint[k] == "ball" and plan.joint_side[k] == side
    if node in structure.pinned:
        return at_its_joint and plan.parent[k] == 0
    return at_its_joint and plan.parent[k] == anchor[0]


def _bar_body(structure: Structure, k: int, plan: Plan, payloads: dict, children: dict) -> str:
    """Bar k's body (frame at its centre, local z along it) with its children inside."""
    centre, rotation, length = _bar_frame(structure, k)
    parent = plan.parent[k]
    if parent:
        parent_centre, parent_rotation, _ = _bar_frame(structure, parent)
        pos, rotation_in_parent = parent_rotation.T @ (centre - parent_centre), parent_rotation.T @ rotation
    else:
        pos, rotation_in_parent = centre, rotation
    rod = structure.bar_mass(k)
    # Point masses on the ends shift the centre of mass along the axis.
    ends = [(-length / 2, payloads.get((k, 0), 0.0)), (length / 2, payloads.get((k, 1), 0.0))]
    mass = rod + sum(m for _, m in ends)
    com = sum(z * m for z, m in ends) / mass
    transverse = rod * length**2 / 12 + rod * com**2 + sum(m * (z - com) ** 2 for z, m in ends)
    axial = AXIAL_INERTIA_FRACTION * transverse
    joint = {
        "free": "<freejoint/>",
        "ball": f'<joint type="ball" pos="0 0 {(plan.joint_side.get(k, 0) - 0.5) * length!r}"/>',
        None: "",
    }[plan.joint[k]]
    inner = "".join(_bar_body(structure, c, plan, payloads, children) for c in children.get(k, []))
    return f"""
    <body name="bar{k}" pos="{_vec(pos)}" quat="{_vec(_quat(rotation_in_parent))}">
      {joint}
      <inertial pos="0 0 {com!r}" mass="{mass!r}" diaginertia="{_vec([transverse, transverse, axial])}"/>
      <geom type="capsule" size="0.01" fromto="0 0 {-length / 2!r} 0 0 {length / 2!r}"/>
      <site name="{bar_site(k, 0)}" pos="0 0 {-length / 2!r}"/>
      <site name="{bar_site(k, 1)}" pos="0 0 {length / 2!r}"/>{inner}
    </body>"""


def _payloads(structure: Structure) -> dict:
    """(bar, side) -> payload mass: the project adds a point mass to the first end at its node."""
    payloads = {}
    for p in structure.scene.get("point_masses", []):
        end = _ends_at(structure)[p["node"]][0]
        payloads[end] = payloads.get(end, 0.0) + p["mass"]
    return payloads


def _world_sites(structure: Structure) -> list:
    """Node sites on the world: pins and nodes on no bar."""
    on_bars = {n for bar in structure.bars for n in bar}
    wanted = sorted(structure.pinned | (set(range(1, len(structure.nodes) + 1)) - on_bars))
    return [
        f'<site name="node{i}" pos="{_vec(structure.nodes[i - 1])}"/>' for i in wanted
    ]


def _cables(structure: Structure, sites: list) -> list:
    lines = []
    for j, cable in enumerate(structure.scene["cables"], start=1):
        kappa, rest = structure.cable_law(j)
        a, b = cable["nodes"]
        lines.append(
            f'<spatial name="cable{j}" stiffness="{kappa!r}" springlength="0 {rest!r}">'
            f'<site site="{sites[a - 1]}"/><site site="{sites[b - 1]}"/></spatial>'
        )
    return lines


def force_input_actuators(structure: Structure) -> list:
    """(node, axis) of each actuator, in actuator order."""
    return [(n, axis) for n in structure.scene.get("force_inputs", []) for axis in range(3)]


def _actuators(structure: Structure, sites: list) -> list:
    lines = []
    for node, axis in force_input_actuators(structure):
        gear = [0.0] * 6
        gear[axis] = 1.0
        lines.append(
            f'<general name="node{node}.f{"xyz"[axis]}" site="{sites[node - 1]}" '
            f'refsite="{WORLD_FRAME_SITE}" gear="{_vec(gear)}"/>'
        )
    return lines


def mjcf(structure: Structure, settings: MujocoSettings = MujocoSettings()) -> str:
    """The MJCF document of the structure."""
    check_supported(structure)
    sites = node_sites(structure)
    payloads = _payloads(structure)
    plan = tree_plan(structure) if settings.joints == "tree" else equality_plan(structure)
    children = {}
    for k in range(1, len(structure.bars) + 1):
        children.setdefault(plan.parent[k], []).append(k)
    bodies = [_bar_body(structure, k, plan, payloads, children) for k in children[0]]
    connects = [f'<connect site1="{a}" site2="{b}"/>' for a, b in plan.connects]
    name = quoteattr(structure.scene.get("name", "tensegrity"))
    s = settings
    return f"""<mujoco model={name}>
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{s.timestep!r}" integrator="{s.integrator}" gravity="{_vec(structure.gravity())}"
          solver="{s.solver}" iterations="{s.iterations}" tolerance="{s.tolerance!r}">
    <flag contact="disable"/>
  </option>
  <default>
    <equality solref="{_vec(s.solref)}" solimp="{_vec(s.solimp)}"/>
    <geom contype="0" conaffinity="0"/>
  </default>
  <worldbody>
    <site name="{WORLD_FRAME_SITE}"/>
    {chr(10).join('    ' + w for w in _world_sites(structure))}
    {''.join(bodies)}
  </worldbody>
  <equality>
    {chr(10).join('    ' + c for c in connects)}
  </equality>
  <tendon>
    {chr(10).join('    ' + c for c in _cables(structure, sites))}
  </tendon>
  <actuator>
    {chr(10).join('    ' + a for a in _actuators(structure, sites))}
  </actuator>
</mujoco>
"""


def build(structure: Structure, settings: MujocoSettings = MujocoSettings()) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(mjcf(structure, settings))


STATE_SPEC = mujoco.mjtState.mjSTATE_FULLPHYSICS


class NodeReader:
    """Node positions (n_nodes × 3, m) from MuJoCo states, through the node sites."""

    def __init__(self, model: mujoco.MjModel, structure: Structure):
        self.model = model
        self.data = mujoco.MjData(model)
        self.site_ids = np.array(
            [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, s) for s in node_sites(structure)]
        )

    def positions(self, state: np.ndarray) -> np.ndarray:
        mujoco.mj_setState(self.model, self.data, state, STATE_SPEC)
        mujoco.mj_kinematics(self.model, self.data)
        return self.data.site_xpos[self.site_ids].copy()


def initial_state(model: mujoco.MjModel) -> np.ndarray:
    """The model's start (the scene's geometry at rest) as a full physics state."""
    data = mujoco.MjData(model)
    mujoco.mj_resetData(model, data)
    state = np.empty(mujoco.mj_stateSize(model, STATE_SPEC))
    mujoco.mj_getState(model, data, state, STATE_SPEC)
    return state


def controls(structure: Structure, forces: dict) -> np.ndarray:
    """The constant actuator controls for forces {node: (fx, fy, fz)}, N."""
    return np.array(
        [forces.get(node, (0.0, 0.0, 0.0))[axis] for node, axis in force_input_actuators(structure)]
    )


def cable_tensions(model: mujoco.MjModel, state: np.ndarray) -> np.ndarray:
    """Each tendon's tension at a state, N: κ (length − L) above L, 0 below."""
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, state, STATE_SPEC)
    mujoco.mj_forward(model, data)
    stretch = data.ten_length - model.tendon_lengthspring[:, 1]
    return model.tendon_stiffness * np.maximum(stretch, 0.0)
