"""dm_control soccer as a throughput peer: one short timed run with the egocentric cameras rendered."""

from legged.soccer.peer_dm_control import measure_dm_control_soccer

KEYS = {"peer", "team_size", "n_agents", "camera", "batch_size", "steps", "env_steps_per_s", "agent_steps_per_s",
        "control_dt", "physics_dt", "camera_size", "dm_control_version", "mujoco_version"}


def test_measure_one_v_one_with_camera():
    result = measure_dm_control_soccer(team_size=1, camera=True, batch_size=1, steps=3)
    assert KEYS <= result.keys()
    assert result["env_steps_per_s"] > 0
    assert result["agent_steps_per_s"] == result["env_steps_per_s"] * 2
    assert result["n_agents"] == 2
    assert result["camera"] is True and result["camera_size"] == (40, 30)
    assert result["camera_obs_shape"] == (30, 40, 3)
    assert result["control_dt"] == 0.025 and result["physics_dt"] == 0.005
