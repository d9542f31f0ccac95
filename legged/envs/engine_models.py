"""The models a legged task hands each physics engine: MJX's (randomised per episode, one friction cone per
compiled model) and the native engine's (a contact sensor per watched geom, randomised fields per simulation), and the
contact read-out from MJX's data. A mixin of legged.envs.base.LeggedEnv, which sets the attributes used here."""

from __future__ import annotations

import copy
import functools

import jax
import mujoco
import numpy as np

from legged.envs.contacts import MjxContactReader
from legged.envs.randomize import mjx_fields, randomized_fields
from legged.robots.models import mjx_model_of
from legged.worlds.mjcf import compile_scene


class EngineModels:
    """The task's models in MJX and in the native engine (needs mj_model, robot, terrain, scene, config, _feet,
    _body_geoms, _base_fields and _trunk, set by LeggedEnv)."""

    @functools.cached_property
    def mjx_model(self):
        """The model in MJX, built on first use (native physics never needs it); an error naming the cause
        for a robot model MJX cannot run (RobotModelError)."""
        with jax.ensure_compile_time_eval():  # concrete arrays even when first needed inside a traced function
            return mjx_model_of(self.mj_model, self.robot)

    @functools.cached_property
    def _contacts(self) -> MjxContactReader:
        return MjxContactReader(self.mj_model, self.mjx_model, np.concatenate([self._feet, self._body_geoms]))

    def with_cone(self, cone: int):
        """This task with its model's friction cone `cone` (mujoco.mjtCone), for MJX, which compiles one cone into its
        programs where the native engine takes each robot's draw (policies.evaluate.mjx_cone_envs)."""
        out = copy.copy(self)
        out.mj_model = copy.copy(self.mj_model)
        out.mj_model.opt.cone = cone
        for cached in ("mjx_model", "_contacts"):  # built again from the new model when first needed
            vars(out).pop(cached, None)
        return out

    def model_with(self, dr: dict):
        """The MJX model with randomisation `dr` applied (the nominal model when disabled)."""
        if not self.config.randomization.enabled:
            return self.mjx_model
        return self.mjx_model.replace(**mjx_fields(self.mjx_model, randomized_fields(self._base_fields, dr,
                                                                                     self._trunk)))

    def mjx_model_for(self, info: dict):
        return self.model_with(info["dr"])

    def native_model_fields(self, info: dict, rows: np.ndarray) -> dict:
        if not self.config.randomization.enabled:
            return {}
        dr = jax.tree_util.tree_map(lambda x: np.asarray(x)[rows], info["dr"])
        nominal = {k: np.array(v) for k, v in self._base_fields.items()}
        return randomized_fields(nominal, dr, self._trunk, xp=np)

    @property
    def watched_geoms(self) -> np.ndarray:
        return np.concatenate([self._feet, self._body_geoms])

    def native_model(self) -> mujoco.MjModel:
        """The scene with a contact sensor on every watched geom, for the native engine."""
        names = tuple(self.robot.feet_geoms) + tuple(self.robot.body_geoms)
        model = compile_scene(self.terrain, self.robot, self.scene, contact_sensors=names)
        model.opt.timestep = self.config.sim_dt
        return model

    def contact_forces(self, data) -> jax.Array:
        """Normal contact force on each foot, then on each body geom (N), of an MJX data."""
        return self._contacts(data)
