"""Spheres on height fields in MJX against MuJoCo itself (legged.mjx_collisions).

The field is a strip of floor sampled every 5 cm, as the confined worlds are, with a void 15 cm long and 1 m deep
across it and a 10 cm step: the steep triangles where MJX's own sphere-prism test reported contacts over a metre
deep with nearly horizontal normals above the rim. A free sphere of the size of Go1's trunk spheres (and one of its
feet's) is put at a sweep of places, and MJX's contacts are compared with the true distance (the field is a polyline
along x) and with native MuJoCo's (the project's scenes collide through libccd: legged.worlds.mjcf).
"""

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest
from mujoco import mjx

from legged import mjx_collisions
from legged.robots.go1 import GO1
from legged.robots.models import mjx_model_of

RES = 0.05
VOID = (1.0, 1.15)
STEP = 1.6
"""The floor drops by 1 m between x = 1.0 and 1.15 m and rises by 10 cm at x = 1.6 m."""


def _floor(x: np.ndarray) -> np.ndarray:
    return np.where((x > VOID[0] - 1e-9) & (x < VOID[1] + 1e-9), -1.0, 0.0) + np.where(x >= STEP - 1e-9, 0.1, 0.0)


def _model(radius: float) -> mujoco.MjModel:
    xs, ys = np.arange(0.0, 2.0 + 1e-9, RES), np.arange(-0.25, 0.25 + 1e-9, RES)
    heights = np.repeat(_floor(xs)[None], len(ys), axis=0)  # rows along y
    lo, span = heights.min(), heights.max() - heights.min()
    spec = mujoco.MjSpec()
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_NATIVECCD
    spec.add_hfield(name="floor", nrow=len(ys), ncol=len(xs), size=[1.0, 0.25, span, 0.1],
                    userdata=((heights - lo) / span).ravel().tolist())
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_HFIELD, hfieldname="floor", pos=[1.0, 0.0, lo])
    body = spec.worldbody.add_body(name="ball")
    body.add_freejoint()
    body.add_geom(name="ball", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[radius, 0, 0])
    return spec.compile()


def _places(radius: float) -> np.ndarray:
    """Sphere centres along the strip: resting 4 mm deep, just clear (5 mm) and high above the floor (21 cm)."""
    xs = np.arange(0.6, 1.9, 0.0125)
    ground = np.maximum(_floor(xs - radius), np.maximum(_floor(xs), _floor(xs + radius)))  # the floor under it
    return np.array([(x, 0.01, g + radius + gap) for x, g in zip(xs, ground) for gap in (-0.004, 0.005, 0.21)])


def _native(model: mujoco.MjModel, places: np.ndarray) -> list[np.ndarray]:
    data, out = mujoco.MjData(model), []
    for p in places:
        data.qpos[:3], data.qpos[3:] = p, (1, 0, 0, 0)
        mujoco.mj_forward(model, data)
        out.append(np.array([c.dist for c in data.contact[:data.ncon]]))
    return out


def _mjx(model: mujoco.MjModel, places: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(distances, normals' z) of MJX's contact slots at each place (inactive slots: distance >= 0)."""
    m = mjx.put_model(model)
    d0 = mjx.make_data(m)

    @jax.jit
    @jax.vmap
    def collide(p):
        d = mjx.kinematics(m, d0.replace(qpos=d0.qpos.at[:3].set(p).at[3].set(1.0)))
        d = mjx.collision(m, d)
        return d._impl.contact.dist, d._impl.contact.frame[:, 0, 2]

    dist, nz = collide(jnp.asarray(places, jnp.float32))
    return np.asarray(dist), np.asarray(nz)


@pytest.fixture
def project_collider():
    """MJX's collision table with the project's (height field, sphere) function (as every project MJX model has)."""
    mjx_collisions.install()


def _exact_gap(place: np.ndarray, radius: float) -> float:
    """The sphere's true distance to the floor (negative: its depth): the field's surface is the polyline of its
    samples along x, the same at every y (both triangles of a cell lie in one plane)."""
    xs = np.arange(0.0, 2.0 + 1e-9, RES)
    a, b = np.stack([xs[:-1], _floor(xs[:-1])], 1), np.stack([xs[1:], _floor(xs[1:])], 1)
    c = np.array([place[0], place[2]])
    t = np.clip(np.sum((c - a) * (b - a), 1) / np.sum((b - a) ** 2, 1), 0, 1)
    to_surface = float(np.min(np.linalg.norm(a + t[:, None] * (b - a) - c, axis=1)))
    below = place[2] < np.interp(place[0], xs, _floor(xs))
    return -to_surface - radius if below else to_surface - radius


@pytest.mark.parametrize("radius", [0.057, 0.023])
def test_mjx_spheres_meet_a_height_field_where_mujoco_does(project_collider, radius):
    model = _model(radius)
    places = _places(radius)
    native = _native(model, places)
    dist, nz = _mjx(model, places)
    for k, (p, reference) in enumerate(zip(places, native)):
        exact, touching = _exact_gap(p, radius), dist[k] < 0
        # MuJoCo (libccd, prism by prism) is within 3 mm of the truth where it touches, and misses nothing
        assert (exact < 0) == (reference.size > 0) and (reference.size == 0 or abs(reference.min() - exact) < 3e-3)
        if exact > 0:
            assert not touching.any(), f"a contact MuJoCo does not have at {p}: {dist[k][touching]}"
            continue
        assert touching.any(), f"no contact at {p}, {-exact:.4f} m deep"
        assert abs(dist[k].min() - exact) < 5e-4, (p, dist[k], exact, reference)
        assert (nz[k][touching] > 0.0).all(), f"a normal pointing down at {p}"
        if p[0] < VOID[0] - radius - RES or VOID[1] + radius + RES < p[0] < STEP - radius - RES:
            # the deepest contact is the floor's, straight up; the others (within 1 mm of it, MJX's rule) are the
            # floor seen from a neighbouring triangle's edge, a few degrees off
            assert nz[k][dist[k].argmin()] > 0.999 and (nz[k][touching] > 0.96).all(), (p, nz[k][touching])
    # 21 cm above the floor, nowhere a contact (MJX's own test found them over the void's rim)
    assert not (dist[2::3] < 0).any()


def test_mjx_own_sphere_test_finds_contacts_high_above_a_void(project_collider):
    """Why the project replaces it: with MJX 3.17's function, a trunk sphere 21 cm above the rim of the void touches
    the floor a metre deep. When this fails, MJX has been fixed and legged.mjx_collisions can go."""
    model = _model(0.057)
    places = np.array([(x, 0.01, 0.057 + 0.21) for x in np.arange(VOID[0] - 0.05, VOID[1] + 0.05, 0.005)])
    with mjx_collisions.mjx_own():
        dist, nz = _mjx(model, places)
    assert dist.min() < -0.5
    assert abs(nz[np.unravel_index(dist.argmin(), dist.shape)]) < 0.2
    assert mjx_collisions.installed()  # put back


def test_the_projects_mjx_models_collide_spheres_through_it():
    with mjx_collisions.mjx_own():
        assert not mjx_collisions.installed()
        mjx_model_of(_model(0.023), GO1)
        assert mjx_collisions.installed()
