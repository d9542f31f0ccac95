"""Realise a terrain as a MuJoCo model (built with MjSpec): floor and ceiling height fields, the robot, and explicit
contact pairs.

The ceiling is a height field turned upside down (180 degrees about x), so both surfaces are exact
copies of the height maps, triangulated the way MuJoCo triangulates every height field.
"""

from __future__ import annotations

import dataclasses
import functools
from pathlib import Path

import mujoco
import numpy as np

from legged.robots.spec import RobotSpec
from legged.worlds.terrain import Terrain

FLOOR_GEOM = "floor"
CEILING_GEOM = "ceiling"
TERRAIN_GROUP = 0
"""Geom group of floor and ceiling (ray casts for height scans look at this group only)."""


@dataclasses.dataclass(frozen=True)
class SceneOptions:
    """How a terrain and a robot are put together into one model."""

    flat: bool = False
    """Use an infinite plane for the floor and no ceiling (flat-ground tasks)."""
    ceiling: bool = True
    """Realise the ceiling map as a height field (rough ground has none within reach)."""
    collide_trunk: bool = True
    """Add trunk-floor and trunk-ceiling contact pairs."""
    collide_legs: bool = False
    """Add thigh and calf contact pairs with the floor, and thighs with the ceiling (slow in MJX)."""
    friction: float = 0.8
    """Sliding friction of every contact pair."""
    ceiling_alpha: float = 0.35
    """Opacity of the ceiling in renderers (so the robot inside a tunnel stays visible)."""
    foot_condim: int | None = None
    """Contact dimension of the feet's pairs with the floor (None: the one MuJoCo gives the robot's foot geom; 6 adds
    torsional and rolling friction, whose coefficients the randomisation can scale: RandomizationConfig.contact_spin)."""


def _add_hfield(spec: mujoco.MjSpec, name, heights, centre, top_z, flipped, rgba, res, thickness=0.1):
    """Add a height-field asset and geom; a flipped one hangs from `top_z` with `heights` as depths."""
    lo, hi = float(heights.min()), float(heights.max())
    rng = max(hi - lo, 1e-4)
    # MuJoCo height fields have rows along y (from -y up: MjSpec's order; MJCF's `elevation` text lists them from +y
    # down) and columns along x; the maps are [x, y]
    data = ((heights - lo) / rng).T
    nrow, ncol = data.shape
    spec.add_hfield(name=name, nrow=nrow, ncol=ncol, size=[(ncol - 1) * res / 2, (nrow - 1) * res / 2, rng, thickness],
                    userdata=data.ravel().tolist())
    pos = [centre[0], centre[1], top_z - lo if flipped else lo]
    quat = [0, 1, 0, 0] if flipped else [1, 0, 0, 0]
    spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_HFIELD, hfieldname=name, group=TERRAIN_GROUP,
                            rgba=rgba, contype=0, conaffinity=0, pos=pos, quat=quat)


MINDIST = 1
"""The contact sensor's reduction that keeps the deepest contacts (MJCF's reduce="mindist")."""
CONTACT_SLOTS = 16
"""Contacts per watched geom that its contact sensor reports (the deepest ones): the sum of their normal
forces is exact while a geom has at most this many (Go1 on the confined height fields: at most 7 seen)."""


_FLOOR_PROBE = """<mujoco><worldbody><geom type="plane" size="0 0 1"/>
<body pos="0 0 0.099"><freejoint/><geom type="sphere" size="0.1" {attrs}/></body></worldbody></mujoco>"""


@functools.lru_cache(maxsize=256)
def _mixed_with_floor(attrs: str) -> tuple:
    """(condim, friction[5], solref[2], solimp[5]) of a contact between a geom with contact attributes `attrs`
    and the scene's floor (MuJoCo's default contact parameters), as MuJoCo itself mixes them."""
    model = mujoco.MjModel.from_xml_string(_FLOOR_PROBE.format(attrs=attrs))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    c = data.contact[0]
    return int(c.dim), tuple(c.friction), tuple(c.solref), tuple(c.solimp)


def pair_attributes(robot_model: mujoco.MjModel, geom: str | int, friction: float) -> dict:
    """MjSpec.add_pair's attributes of the explicit contact pair of robot geom `geom` (name or id) with a floor or
    ceiling: the contact the robot model's own geom makes with a plain floor (condim, solref, solimp, torsional and
    rolling friction, by MuJoCo's mixing rules, its priority included; margin and gap the geom's), with the scene's
    sliding `friction`."""
    g = robot_model.geom(geom)
    fmt = lambda v: " ".join(f"{x:.9g}" for x in np.ravel(v))
    attrs = (f'condim="{int(g.condim[0])}" friction="{fmt(g.friction)}" solref="{fmt(g.solref)}" '
             f'solimp="{fmt(g.solimp)}" solmix="{fmt(g.solmix)}" priority="{int(g.priority[0])}"')
    condim, mixed, solref, solimp = _mixed_with_floor(attrs)
    return dict(condim=condim, friction=[friction, friction, *mixed[2:]], solref=list(solref), solimp=list(solimp),
                margin=float(g.margin[0]), gap=float(g.gap[0]))


def scene_spec(terrain: Terrain, robot: RobotSpec, options: SceneOptions = SceneOptions(),
               contact_sensors: tuple[str, ...] = ()) -> mujoco.MjSpec:
    """The robot's model with the terrain and contact pairs added, and a contact sensor (forces of the CONTACT_SLOTS
    deepest contacts, each normal first) on every geom of `contact_sensors`; not compiled."""
    if not robot.mjcf_path.is_file():
        raise FileNotFoundError(f"robot model not found: {robot.mjcf_path} (reinstall the package assets)")
    spec = mujoco.MjSpec.from_file(str(robot.mjcf_path))
    spec.modelname = f"{robot.name}_{'flat' if options.flat else 'confined'}"
    spec.add_texture(name="grid", type=mujoco.mjtTexture.mjTEXTURE_2D, builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER,
                     width=256, height=256, rgb1=[0.35, 0.4, 0.45], rgb2=[0.3, 0.35, 0.4])
    grid = spec.add_material(name="grid", texrepeat=[8, 8], texuniform=True)
    grid.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "grid"
    spec.worldbody.add_light(name="sun", pos=[0, 0, 6], dir=[0, 0, -1], type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL)
    res = terrain.resolution
    centre = terrain.origin + res * (np.array(terrain.shape) - 1) / 2
    surfaces = [FLOOR_GEOM]
    if options.flat:
        spec.worldbody.add_geom(name=FLOOR_GEOM, type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05], material="grid",
                                group=TERRAIN_GROUP, contype=0, conaffinity=0)
    else:
        # MuJoCo 3.17's native convex collider gives a foot sphere on a height field contacts on the walls
        # between the field's triangular prisms (horizontal normals, 2 cm deep): the feet wedge and the robot
        # sinks. libccd gives the right, upward contacts (tests/test_physics_terrain.py checks it).
        spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_NATIVECCD
        _add_hfield(spec, FLOOR_GEOM, terrain.floor, centre, None, False, [0.55, 0.5, 0.45, 1], res)
        if options.ceiling:
            top = float(terrain.ceiling_top)
            depth = (top - terrain.ceiling)[:, ::-1]  # depth below `top`; 180 deg about x mirrors y
            _add_hfield(spec, CEILING_GEOM, depth, centre, top, True, [0.45, 0.55, 0.7, options.ceiling_alpha], res)
            surfaces.append(CEILING_GEOM)
    pairs = [(g, FLOOR_GEOM) for g in robot.feet_geoms]
    if options.collide_trunk:
        pairs += [(g, s) for g in robot.body_geoms for s in surfaces]
    if options.collide_legs:
        pairs += [(g, FLOOR_GEOM) for g in robot.thigh_geoms + robot.calf_geoms]
        pairs += [(g, s) for g in robot.thigh_geoms for s in surfaces[1:]]
    alone = mujoco.MjModel.from_xml_path(str(robot.mjcf_path))
    for geom, surface in pairs:
        attributes = pair_attributes(alone, geom, options.friction)
        if options.foot_condim is not None and geom in robot.feet_geoms and surface == FLOOR_GEOM:
            attributes["condim"] = options.foot_condim
        spec.add_pair(geomname1=geom, geomname2=surface, **attributes)
    force = 1 << int(mujoco.mjtConDataField.mjCONDATA_FORCE)  # data="force"
    for geom in contact_sensors:  # intprm: the data fields, the reduction (1: the deepest first), the slots
        spec.add_sensor(name=f"contact_{geom}", type=mujoco.mjtSensor.mjSENS_CONTACT, objtype=mujoco.mjtObj.mjOBJ_GEOM,
                        objname=geom, intprm=[force, MINDIST, CONTACT_SLOTS])
    return spec


def scene_xml(terrain: Terrain, robot: RobotSpec, options: SceneOptions = SceneOptions(),
              contact_sensors: tuple[str, ...] = ()) -> str:
    """Standalone MJCF text of `scene_spec`."""
    return scene_spec(terrain, robot, options, contact_sensors).to_xml()


def compile_scene(terrain: Terrain, robot: RobotSpec, options: SceneOptions = SceneOptions(),
                  contact_sensors: tuple[str, ...] = ()) -> mujoco.MjModel:
    """Compiled MjModel of the scene (the one source of truth for MJX, native MuJoCo and viewers); the native
    engine's copy adds `contact_sensors` (read-outs only: the physics is the same)."""
    return scene_spec(terrain, robot, options, contact_sensors).compile()


def write_world(world, robot: RobotSpec, out_dir) -> dict:
    """Write DIR/world.npz (the data) and DIR/world.xml (standalone MJCF with the robot at the start)."""
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OSError(f"cannot create output directory {out}: {exc.strerror}") from exc
    npz = world.save(out / "world.npz")
    spec = scene_spec(Terrain.from_worlds([world]), robot)
    start = [*world.start[:2], world.start[2] + 0.02]
    spec.body(robot.root_body).pos = start
    for key in spec.keys:  # keyframes would teleport the robot back to the origin
        key.qpos = [*start, *list(key.qpos)[3:]]
    path = out / "world.xml"
    path.write_text(spec.to_xml())
    mujoco.MjModel.from_xml_path(str(path))  # fail here, not in the user's viewer
    return {"npz": str(npz), "xml": str(path)}
