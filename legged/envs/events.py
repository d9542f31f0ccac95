"""Events counted as they happen: the metrics a vector environment sums over an episode (`events/<name>`,
legged.envs.vector.SUMMED), so an evaluation reports how often something happened, not the state at the last step.

- `events/falls`: 1 at each step where the task's fall rule starts to hold (a robot that falls, gets up and
  falls again counts 2); where a fall ends the episode (the Go1 tasks) at most 1 per episode.
- `events/seconds_down`: the control period at each step where the fall rule holds (time spent fallen).
- `events/getups_started`, `events/getups_completed` (soccer players with a get-up skill): 1 at each step where
  the skill takes the joints, and where it hands them back with the robot standing (a get-up cut short by a
  kick-off, which puts every robot back on its feet, is started but not completed).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


def fall_events(began: jax.Array, down: jax.Array, dt: float) -> dict:
    """`events/falls` and `events/seconds_down` of one step: `began` where the fall rule starts to hold, `down`
    where it holds (boolean arrays of any shape: one entry per robot), `dt` the control period in seconds."""
    return {"events/falls": began.astype(jnp.float32), "events/seconds_down": down.astype(jnp.float32) * dt}


def getup_events(was: jax.Array, now: jax.Array) -> dict:
    """`events/getups_started` and `events/getups_completed` of one step from whether each robot's get-up skill
    had the joints before it (`was`) and has them after it (`now`)."""
    return {"events/getups_started": (now & ~was).astype(jnp.float32),
            "events/getups_completed": (was & ~now).astype(jnp.float32)}
