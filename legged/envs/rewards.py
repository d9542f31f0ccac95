"""Reward shaping pieces shared by tasks."""

import jax.numpy as jnp


def tracking(error_sq, sigma):
    """exp(-error^2 / sigma): 1 when a command is tracked exactly, decaying with the squared error."""
    return jnp.exp(-error_sq / sigma)


def wrap_angle(angle):
    """Angle wrapped to (-pi, pi]."""
    return jnp.arctan2(jnp.sin(angle), jnp.cos(angle))
