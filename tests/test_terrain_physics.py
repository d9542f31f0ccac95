"""Go1 on the generated height fields in native MuJoCo: its feet meet the floor from above.

MuJoCo 3.17's native convex collider put a foot sphere's contacts on the walls between a height field's
triangular prisms (horizontal normals, 2 cm deep): feet wedged and Go1 sank at its standing pose. The
scenes therefore switch to libccd (legged.worlds.mjcf); this pins the effect.
"""

import jax
import mujoco
import numpy as np

from legged.tasks import make


def test_go1_stands_on_the_height_field_with_upward_contacts():
    env = make("confined-waypoints")
    model = env.native_model()
    assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_NATIVECCD
    spawn = jax.jit(env.spawn)(jax.random.PRNGKey(0))
    data = mujoco.MjData(model)
    data.qpos[:], data.ctrl[:] = np.asarray(spawn.qpos), np.asarray(spawn.ctrl)
    for _ in range(400):  # 2 s at the standing pose
        mujoco.mj_step(model, data)
    floor = float(env.floor_height(data.qpos[:2]))
    assert data.qpos[2] - floor > 0.25
    normals = np.array([c.frame[:3] for c in data.contact[:data.ncon]])
    assert len(normals) and (normals[:, 2] > 0.9).all()
    assert min(c.dist for c in data.contact[:data.ncon]) > -0.005
