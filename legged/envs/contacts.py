"""Contact read-out (normal force per geom of interest) for MJX and for native MuJoCo.

The only physics-engine-specific part of the environments: everything else (observations, rewards,
terminations) is shared code that receives a `(n_geoms,)` array of normal forces from here.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from mujoco import mjx


class MjxContactReader:
    """Normal contact force on each listed geom, from an MJX data (static efc layout, jittable)."""

    def __init__(self, mj_model: mujoco.MjModel, mjx_model, geom_ids: np.ndarray):
        # The contact layout (which geoms, which constraint rows) is static in MJX: one jitted collision
        # pass on the initial data reveals it (an eager mjx.forward took over a minute on a CPU).
        # (compiled ahead and called: that runs now even when the reader is first needed inside a traced function)
        with jax.ensure_compile_time_eval():
            data = mjx.make_data(mjx_model)
        contact = jax.jit(mjx.collision).lower(mjx_model, data).compile()(mjx_model, data)._impl.contact
        geoms = np.asarray(contact.geom)
        addr = np.asarray(contact.efc_address)
        dims = np.asarray(contact.dim)
        # A pyramidal cone's normal force is the sum of its 2 (dim - 1) edge forces (one row for a frictionless
        # contact); an elliptic cone's is its first row.
        if mj_model.opt.cone == mujoco.mjtCone.mjCONE_PYRAMIDAL:
            rows = np.where(dims > 1, 2 * (dims - 1), 1)
        else:
            rows = np.ones_like(dims)
        width = int(rows.max()) if len(rows) else 0
        self._rows = np.stack([addr + k for k in range(width)], -1) if len(addr) else None
        self._row_mask = (np.arange(width)[None] < rows[:, None]).astype(np.float32) if len(addr) else None
        self._valid = (addr >= 0).astype(np.float32)
        # match[c, g] = 1 when contact c touches the g-th geom of interest.
        self._match = ((geoms[:, :1] == geom_ids[None]) | (geoms[:, 1:] == geom_ids[None])).astype(np.float32)
        self._num_geoms = len(geom_ids)

    def __call__(self, data) -> jax.Array:
        if self._rows is None:
            return jnp.zeros(self._num_geoms)
        normal = (data._impl.efc_force[self._rows] * self._row_mask).sum(-1) * self._valid
        return normal @ self._match


def native_contact_forces(model: mujoco.MjModel, data: mujoco.MjData, geom_ids: np.ndarray) -> np.ndarray:
    """Same read-out as MjxContactReader for a native MjData."""
    out = np.zeros(len(geom_ids))
    wrench = np.zeros(6)
    for i in range(data.ncon):
        c = data.contact[i]
        hit = (geom_ids == c.geom1) | (geom_ids == c.geom2)
        if hit.any() and c.efc_address >= 0:
            mujoco.mj_contactForce(model, data, i, wrench)
            out[hit] += wrench[0]
    return out
