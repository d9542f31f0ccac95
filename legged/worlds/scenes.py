"""Navigation scenes written from MuJoCo primitives, as a user would build them: builders, reading, writing.

A scene is a standalone MJCF file: boxes and cylinders on a floor (a plane, or boxes over a deeper plane where the
floor has voids), and three things a navigation needs, kept in the file itself:
- sites `start` and `goal`: the body centre's start and goal (x, y, z);
- `<numeric name="time_limit_s">`: the seconds a navigation may take (its path length at `SPEED` twice over,
  plus `SLACK_S`);
- `<text name="description">`: what the scene holds.

The benchmark's family of them is legged.worlds.bench_scenes. `read_scene` reads any scene file with those
entries.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import mujoco
import numpy as np

BODY_Z = 0.27
"""Height of the Go1's body centre above the floor at a scene's start and goal, metres."""
SPEED = 1.0
"""The speed the time limits are written for, m/s (a follower's speed limit)."""
SLACK_S = 10.0
"""Seconds added to every time limit (standing up, turning in place, one replan)."""
WALL = 0.05
"""Half thickness of walls, roofs and floor slabs, metres."""


class SceneError(ValueError):
    """A scene file cannot be used for navigation: the message names the file and what is missing."""


@dataclasses.dataclass(frozen=True)
class Scene:
    """One navigation scene: its MJCF text and the entries a navigation reads from it."""

    name: str
    """File stem, e.g. `corridor-w100-roof50`."""
    xml: str
    """Standalone MJCF text (start, goal, time limit and description inside)."""
    start: tuple[float, float, float]
    """Body centre at the start, metres."""
    goal: tuple[float, float, float]
    """Body centre at the goal, metres."""
    time_limit_s: float
    """Seconds the navigation may take."""
    description: str
    """What the scene holds, one line."""


def _f(values) -> str:
    return " ".join(f"{float(v):.4f}" for v in values)


def box(name: str, centre, half, yaw: float = 0.0) -> str:
    """An MJCF box geom (yaw about z, radians)."""
    turn = f' euler="0 0 {yaw:.6f}"' if yaw else ""
    return f'    <geom name="{name}" type="box" pos="{_f(centre)}" size="{_f(half)}"{turn}/>'


def pillar(name: str, x: float, y: float, radius: float, height: float) -> str:
    """A vertical cylinder standing on z = 0."""
    return (f'    <geom name="{name}" type="cylinder" pos="{_f((x, y, height / 2))}" '
            f'size="{radius:.4f} {height / 2:.4f}"/>')


def pipe(name: str, x: float, y: float, underside: float, radius: float, length: float, yaw: float = 0.0) -> str:
    """A horizontal cylinder across the way at x, y (its axis along y turned by `yaw`), its underside at `underside`."""
    return (f'    <geom name="{name}" type="cylinder" pos="{_f((x, y, underside + radius))}" '
            f'size="{radius:.4f} {length / 2:.4f}" euler="{math.pi / 2:.6f} 0 {yaw:.6f}"/>')


def offset(points: np.ndarray, d: float) -> np.ndarray:
    """The polyline `points` (n, 2) moved `d` to its left, corners mitred."""
    points = np.asarray(points, float)
    dirs = np.diff(points, axis=0)
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    normals = np.stack([-dirs[:, 1], dirs[:, 0]], 1)
    out = [points[0] + d * normals[0]]
    for k in range(1, len(points) - 1):
        n = normals[k - 1] + normals[k]
        n /= np.linalg.norm(n)
        out.append(points[k] + d * n / max(float(n @ normals[k]), 0.2))
    out.append(points[-1] + d * normals[-1])
    return np.array(out)


def wall_along(name: str, line: np.ndarray, height: float, z0: float = 0.0) -> list[str]:
    """Walls of half thickness WALL whose inner face follows the polyline `line`, from z0 to z0 + height."""
    geoms = []
    for k, (a, b) in enumerate(zip(line[:-1], line[1:])):
        v = b - a
        length = float(np.linalg.norm(v))
        centre = (a + b) / 2
        geoms.append(box(f"{name}_{k}", (centre[0], centre[1], z0 + height / 2), (length / 2 + WALL, WALL, height / 2),
                         math.atan2(v[1], v[0])))
    return geoms


def corridor(name: str, points, width: float, roof: float | None, wall_height: float = 1.2,
             closed: bool = True) -> list[str]:
    """Walls (and a roof slab whose underside is at `roof`, None: open sky) along the polyline `points`; `closed`:
    end walls across both ends too, so that the corridor is the only way between them."""
    points = np.asarray(points, float)
    geoms = (wall_along(f"{name}_left", offset(points, width / 2 + WALL), wall_height)
             + wall_along(f"{name}_right", offset(points, -width / 2 - WALL), wall_height))
    if closed:
        for end, (a, b) in (("start", (points[0], points[1])), ("end", (points[-1], points[-2]))):
            v = (a - b) / np.linalg.norm(a - b)
            c = a + WALL * v
            geoms.append(box(f"{name}_{end}_cap", (c[0], c[1], wall_height / 2),
                             (WALL, width / 2 + 2 * WALL, wall_height / 2), math.atan2(v[1], v[0])))
    if roof is not None:
        for k, (a, b) in enumerate(zip(points[:-1], points[1:])):
            v = b - a
            length = float(np.linalg.norm(v))
            centre = (a + b) / 2
            geoms.append(box(f"{name}_roof_{k}", (centre[0], centre[1], roof + WALL),
                             (length / 2 + width / 2 + WALL, width / 2 + 2 * WALL, WALL), math.atan2(v[1], v[0])))
    return geoms


def path_length(points) -> float:
    """Length of a polyline, metres."""
    return float(np.sum(np.linalg.norm(np.diff(np.asarray(points, float), axis=0), axis=1)))


def scene(name: str, description: str, geoms: list[str], route, floor: float = 0.0, goal_z: float | None = None,
          plane_z: float = 0.0) -> Scene:
    """A scene whose robot goes along the polyline `route` (start first, goal last) on a floor at `floor` (start)
    and `goal_z` (the goal's floor, default the same), over a plane at `plane_z`."""
    route = np.asarray(route, float)
    start = (float(route[0, 0]), float(route[0, 1]), floor + BODY_Z)
    goal = (float(route[-1, 0]), float(route[-1, 1]), (floor if goal_z is None else goal_z) + BODY_Z)
    limit = round(2 * path_length(route) / SPEED + SLACK_S, 1)
    xml = "\n".join([
        f'<mujoco model="{name}">',
        '  <compiler angle="radian"/>',
        "  <custom>",
        f'    <numeric name="time_limit_s" data="{limit:g}"/>',
        f'    <text name="description" data="{description}"/>',
        "  </custom>",
        "  <worldbody>",
        f'    <geom name="ground" type="plane" pos="0 0 {plane_z:.4f}" size="0 0 0.05"/>',
        *geoms,
        f'    <site name="start" pos="{_f(start)}" size="0.05"/>',
        f'    <site name="goal" pos="{_f(goal)}" size="0.05"/>',
        "  </worldbody>",
        "</mujoco>", ""])
    return Scene(name, xml, start, goal, limit, description)


def read_model(path) -> mujoco.MjModel:
    """The compiled model of an MJCF scene file; SceneError naming the file and the cause."""
    path = Path(path)
    if not path.is_file():
        raise SceneError(f"scene file not found: {path}")
    if "<mujoco" not in path.read_text(errors="replace"):
        raise SceneError(f"{path} is not an MJCF file (no <mujoco> element)")
    try:
        return mujoco.MjModel.from_xml_path(str(path))
    except ValueError as exc:
        raise SceneError(f"cannot load scene {path}: {str(exc).splitlines()[0]}") from None


def read_scene(path) -> tuple[mujoco.MjModel, Scene]:
    """(compiled model, its Scene) of a navigation scene file; SceneError naming the file and what is missing."""
    path = Path(path)
    model = read_model(path)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    where = {}
    for site in ("start", "goal"):
        sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, site)
        if sid < 0:
            raise SceneError(f"{path} has no site named {site!r} (the body centre's {site} position)")
        where[site] = tuple(float(v) for v in data.site_xpos[sid])
    nid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, "time_limit_s")
    if nid < 0:
        raise SceneError(f'{path} has no <numeric name="time_limit_s"> (seconds the navigation may take)')
    limit = float(model.numeric_data[model.numeric_adr[nid]])
    if not limit > 0:
        raise SceneError(f"{path}: time_limit_s must be > 0, got {limit}")
    tid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TEXT, "description")
    description = ""
    if tid >= 0:
        adr, size = model.text_adr[tid], model.text_size[tid]
        description = bytes(model.text_data[adr:adr + size - 1]).decode()
    return model, Scene(path.stem, path.read_text(), where["start"], where["goal"], limit, description)


def scene_files(directory) -> list[Path]:
    """The scene files of a directory, by name; SceneError when there are none."""
    directory = Path(directory)
    if not directory.is_dir():
        raise SceneError(f"scene directory not found: {directory}")
    files = sorted(directory.glob("*.xml"))
    if not files:
        raise SceneError(f"{directory} holds no scene files (*.xml)")
    return files


def write_scenes(directory, scenes: list[Scene]) -> list[Path]:
    """Write `scenes` as NAME.xml into `directory`; the paths written."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    paths = []
    for s in scenes:
        paths.append(directory / f"{s.name}.xml")
        paths[-1].write_text(s.xml)
    return paths
