"""What the follower's height scans mean does not depend on the scene around them: any roof beyond what can touch
the body reads the same as open sky, and a gap in the floor is seen wherever it lies ahead or under the feet.

The task's hooks are called directly on a spawned episode (no physics, nothing compiled)."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from legged.envs.config import NoiseConfig, RandomizationConfig
from legged.envs.confined import ConfinedConfig, ConfinedEnv
from legged.tasks import default_config
from legged.worlds import Terrain
from legged.worlds.generator import World

RES = 0.05


def _world(roof: float | None, void: tuple[float, float] | None = None) -> World:
    """A 1.2 m wide corridor from x = -2 to 3 with a flat floor at 0, under a roof at `roof` (None: open sky, the
    ceiling 2 m up), with a gap (x from, x to) 0.5 m deep across it."""
    xs, ys = np.arange(-2.1, 3.1 + 1e-9, RES), np.arange(-0.7, 0.7 + 1e-9, RES)
    floor = np.zeros((xs.size, ys.size))
    if void:
        floor[(xs > void[0] + 1e-9) & (xs < void[1] - 1e-9)] = -0.5
    ceiling = np.full_like(floor, 2.0 if roof is None else roof)
    wall = (np.abs(xs[:, None]) > 2.0) & (xs[:, None] < 0) | (xs[:, None] > 3.0) | (np.abs(ys[None, :]) > 0.6)
    top = 2.0
    return World(floor=np.where(wall, top, floor).astype(np.float32), ceiling=np.where(wall, top, ceiling).astype(
        np.float32), resolution=RES, origin=np.array([xs[0], ys[0]]), start=np.array([-1.5, 0.0, 0.27]),
        goal=np.array([2.5, 0.0, 0.27]))


def _scans(world: World, config: ConfinedConfig, x: float = -1.5, z: float = 0.29) -> np.ndarray:
    """(ceiling, floor) scans, each (rows along x, columns along y), of a level body at (x, 0, z) heading +x."""
    env = ConfinedEnv(config, terrain=Terrain.from_worlds([world]))
    view, info = env._spawned_view(jax.random.PRNGKey(0))
    view = view.replace(xpos=view.xpos.at[env._trunk].set(jnp.array([x, 0.0, z])),
                        xmat=view.xmat.at[env._trunk].set(jnp.eye(3)))
    scans, _ = env._exteroception(view, info)
    xs = np.arange(config.scan.x_range[0], config.scan.x_range[1] + 1e-9, config.scan.spacing)
    return np.asarray(scans).reshape(2, len(xs), -1)


def _config(**overrides) -> ConfinedConfig:
    return ConfinedConfig(**{**vars(default_config("confined-waypoints")), "randomization": RandomizationConfig(),
                             "noise": NoiseConfig(), **overrides})


def test_roofs_beyond_reach_and_open_sky_read_alike():
    config = _config()
    assert config.scan.ceiling_clip is not None
    scans = [_scans(_world(roof), config) for roof in (0.6, 1.0, None)]
    for other in scans[1:]:
        np.testing.assert_array_equal(scans[0], other)
    crawl = _scans(_world(0.4), config)  # a roof the body must mind reads as itself
    assert np.allclose(crawl[0], 0.4 - 0.29, atol=1e-5)
    old = _config(scan=dataclasses.replace(config.scan, ceiling_clip=None))  # without the clip they differ
    assert not np.array_equal(_scans(_world(0.6), old)[0], _scans(_world(None), old)[0])


@pytest.mark.parametrize("offset", np.arange(0.0, 0.1, 0.01))
def test_the_narrowest_void_is_seen_ahead_and_under_the_feet(offset):
    """A 10 cm gap, 0.5 m deep, anywhere between the hind feet and 0.8 m ahead, reads as the deepest floor the scan
    gives in at least one row, across the whole corridor."""
    config = _config()
    assert config.scan.spacing <= 0.10 / 2
    clip = config.scan.clip
    for ahead in (-0.2, 0.3, 0.8):
        start = -1.5 + ahead + offset
        floor = _scans(_world(1.0, (start, start + 0.10)), config)[1]
        rows = np.flatnonzero((floor <= -clip + 1e-6).all(axis=1))
        assert rows.size >= 1, (ahead, offset)
        assert (floor[np.setdiff1d(np.arange(len(floor)), rows)] > -0.35).all()  # the rest reads the flat floor
