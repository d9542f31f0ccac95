"""The terrain curriculum shared by tiled tasks: each tile of a terrain has a level, and an episode plays a tile
of the level its environment carries from the episode before (legged_gym's terrain curriculum)."""

from __future__ import annotations

import jax
import jax.numpy as jnp


def pick_tile(rng: jax.Array, carry: dict | None, tile_level: jax.Array, n_levels: int,
              curriculum: bool) -> tuple[jax.Array, jax.Array]:
    """(tile, level) of a new episode. With the curriculum, a random tile of the carried level (level 0 at the
    first reset, a random level once past the hardest); without it, a uniform tile. A carried tile >= 0 (an
    evaluator's choice) wins over both."""
    k_level, k_tile = jax.random.split(rng)
    if carry is None or "level" not in carry or not curriculum:  # (a carry may hold only a randomisation scale)
        level = jnp.int32(0) if curriculum else jax.random.randint(k_level, (), 0, n_levels)
    else:
        level = jnp.where(carry["level"] >= n_levels, jax.random.randint(k_level, (), 0, n_levels), carry["level"])
    weights = jnp.where(tile_level == level, 0.0, -jnp.inf) if curriculum else jnp.zeros(tile_level.shape[0])
    tile = jax.random.categorical(k_tile, weights).astype(jnp.int32)
    if carry is not None and "tile" in carry:
        tile = jnp.where(carry["tile"] >= 0, carry["tile"], tile)
    return tile, tile_level[tile]


def level_carry(level, tile=-1) -> dict:
    """The carry a new episode starts from: its curriculum `level` and a `tile` (-1: drawn at that level),
    each a scalar or one per environment."""
    level = jnp.asarray(level, jnp.int32)
    return {"level": level, "tile": jnp.broadcast_to(jnp.asarray(tile, jnp.int32), level.shape)}


def next_level(level: jax.Array, up: jax.Array, down: jax.Array) -> dict:
    """The carry of a finished episode: one level up, or down (never below 0), and no tile of its own."""
    level = level + up.astype(jnp.int32) - (down & ~up).astype(jnp.int32)
    return level_carry(jnp.maximum(level, 0))
