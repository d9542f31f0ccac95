"""Domain randomisation of a soccer game: ground and ball friction, ball mass and rolling resistance, robot
link masses and motor strength, and where set each robot's payload and centre of mass, servo gains, joint damping,
armature and friction loss, foot contact, action latency, encoder offsets, IMU biases and pushes (the Go1's
quantities: legged.envs.randomize), sampled per episode and applied to the model's fields in both engines (jax.numpy
for MJX models under vmap, numpy rows for native MuJoCo).

Quantities a config leaves unset (None, 0) are not drawn, so runs saved before they existed replay unchanged; their
keys come from separate streams (`fold_in(rng, 1)`, `fold_in(rng, 2)`) for the same reason."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from legged.envs.randomize import draw_model, model_fields, servo_fields
from legged.soccer.layout import BALL, FLOOR_GEOM

FIELDS = ("body_mass", "body_inertia", "body_ipos", "pair_friction", "actuator_gainprm", "actuator_biasprm",
          "dof_damping", "dof_armature", "dof_frictionloss", "pair_solref", "pair_solimp", "pair_margin")
"""Model fields the randomisation changes."""


@dataclasses.dataclass(frozen=True)
class SoccerRandomization:
    """Per-episode randomisation of a soccer game (every robot gets its own masses and motors)."""

    enabled: bool = False
    """Switch for the whole group."""
    floor_friction: tuple[float, float] = (0.5, 1.1)
    """Range of the sliding friction of robot feet (and fallen torsos, heads) on the floor."""
    ball_friction: tuple[float, float] = (0.3, 0.7)
    """Range of the sliding friction of the ball against everything."""
    ball_rolling_friction: tuple[float, float] = (0.002, 0.01)
    """Range of the ball's rolling (and torsional) friction on the floor, metres."""
    ball_mass: tuple[float, float] = (0.15, 0.3)
    """Range of the ball's mass, kg (its inertia scales with it)."""
    link_mass_scale: tuple[float, float] = (0.9, 1.1)
    """Range of the scale of each robot link's mass (and inertia)."""
    motor_strength: tuple[float, float] = (0.85, 1.1)
    """Range of the scale of each servo's torque (its proportional and derivative gains together)."""
    payload: tuple[float, float] | None = None
    """Range of the mass added to each robot's torso, kg (None: not drawn)."""
    com_offset: float = 0.0
    """Each robot's torso centre of mass moves by up to +-this per axis, metres (0: not drawn)."""
    kp_scale: tuple[float, float] | None = None
    """Range of the scale of each robot's proportional gains (all its joints together; None: not drawn)."""
    kd_scale: tuple[float, float] | None = None
    """Range of the scale of each robot's derivative gains (all its joints together; None: not drawn)."""
    joint_damping: tuple[float, float] | None = None
    """Range of each actuated joint's passive damping, N m s/rad, drawn per joint of each robot (None: the model's)."""
    joint_armature: tuple[float, float] | None = None
    """Range of each actuated joint's armature (rotor inertia), kg m^2, per joint of each robot (None: the model's)."""
    joint_frictionloss: tuple[float, float] | None = None
    """Range of each actuated joint's dry friction, N m, per joint of each robot (None: the model's)."""
    contact_softness: tuple[float, float] | None = None
    """Range of the feet's contact softness (legged.envs.config.RandomizationConfig), one draw per game: every robot
    in a game is the same model (None: the model's)."""
    contact_timeconst: tuple[float, float] | None = None
    """Range of the feet's contact time constant (solref[0]) on the floor, seconds, one draw per game (None: the
    model's)."""
    contact_margin: tuple[float, float] | None = None
    """Range of the feet's contact margin on the floor, metres, one draw per game (None: the model's)."""
    latency_s: tuple[float, float] | None = None
    """Range of each robot's action latency, seconds, drawn in whole physics steps: for that long after a control step
    begins its previous joint targets still act (None: none)."""
    encoder_offset: float = 0.0
    """Each joint's angle reads off by a constant uniform in +-this for the episode, radians (0: none)."""
    imu_bias: tuple[float, float] = (0.0, 0.0)
    """Constant biases of each robot's IMU for the episode, uniform in +-these per axis: on the projected gravity
    (unitless) and on the angular velocity (rad/s)."""
    push_interval_s: float = 0.0
    """Seconds between random pushes of every robot (0: none); all are pushed at the same steps of the episode."""
    push_velocity: float = 0.0
    """A push adds a horizontal velocity uniform in +-this per axis to each robot's torso, m/s."""

    def validate(self) -> None:
        """ValueError naming a range that is empty or non-positive."""
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if f.name == "imu_bias":
                if min(value) < 0:
                    raise ValueError(f"randomization.imu_bias must be non-negative, got {value}")
            elif f.name == "payload" and value is not None:
                if not value[0] <= value[1]:
                    raise ValueError(f"randomization.payload must be a range low <= high, got {value}")
            elif isinstance(value, tuple) and not 0 <= value[0] <= value[1]:
                raise ValueError(f"randomization.{f.name} must be a range 0 <= low <= high, got {value}")
        for name in ("com_offset", "encoder_offset", "push_interval_s", "push_velocity"):
            if getattr(self, name) < 0:
                raise ValueError(f"randomization.{name} must be non-negative, got {getattr(self, name)}")


OP3_COVERING = dict(payload=(-0.2, 0.4), com_offset=0.01, kp_scale=(0.9, 1.1), kd_scale=(0.75, 1.25),
                    joint_damping=(0.0, 2.5), joint_armature=(0.03, 0.06),
                    joint_frictionloss=(0.0, 0.06), contact_timeconst=(0.01, 0.025), latency_s=(0.0, 0.02),
                    encoder_offset=0.02, imu_bias=(0.03, 0.05), push_interval_s=10.0, push_velocity=0.15)
"""Ranges that cover every reference model of the OP3 (legged.robots.models): passive joint damping from none (the
project's, whose servo's D term holds it) to MuJoCo Menagerie's 1.084 N m s/rad (kept beside the servo's D term when a
policy runs on Menagerie's model), armature and friction loss around both models' 0.045 and 0.03, the feet's contact
time constant from Menagerie's 0.012 s (its 0.004 mixed with a plain floor) to the project's 0.02, with up to 20 ms
of action latency, small sensor biases and a push of up to 0.15 m/s (the walker's pace) every 10 s; a payload of
-0.2 to +0.4 kg on the 1.35 kg torso with its centre of mass moved up to 1 cm."""


@dataclasses.dataclass(frozen=True)
class SoccerDynamics:
    """Which rows of the model's fields each randomised quantity touches (numpy, static)."""

    robot_bodies: np.ndarray
    """Bool per body: a robot link."""
    ball_body: int
    """Body id of the ball."""
    floor_pairs: np.ndarray
    """Bool per contact pair: robot geom with the floor, or robot with robot."""
    ball_pairs: np.ndarray
    """Bool per contact pair: the ball with anything."""
    ball_floor_pair: int
    """Index of the ball-floor pair (rolling friction)."""
    joint_dofs: np.ndarray
    """One-hot [n_agents * n_joints, nv]: each robot's joint (agent-major, policy order) to its dof."""
    joint_actuators: np.ndarray
    """One-hot [n_agents * n_joints, nu]: each robot's joint to its actuator."""
    foot_pairs: np.ndarray
    """1. for each contact pair of a robot's foot with the floor, [npair]."""
    n_agents: int
    """Robots in the game."""
    torso_bodies: np.ndarray
    """One-hot [n_agents, nbody]: each robot's torso body."""

    @classmethod
    def of(cls, model: mujoco.MjModel, layout) -> "SoccerDynamics":
        names = [model.pair(i).name for i in range(model.npair)]
        ball = np.array([n.startswith(BALL + "~") or n.endswith("~" + BALL) for n in names])
        root = model.body_rootid
        robot = (root != 0) & (root != root[layout.ball_body]) & (np.arange(model.nbody) > 0)
        one_hot = lambda ids, n: np.eye(n, dtype=np.float32)[np.ravel(ids)]
        feet = np.isin(model.pair_geom1, layout.feet_geoms) | np.isin(model.pair_geom2, layout.feet_geoms)
        floor = (model.pair_geom1 == layout.floor_geom) | (model.pair_geom2 == layout.floor_geom)
        return cls(robot_bodies=robot, ball_body=layout.ball_body, floor_pairs=~ball, ball_pairs=ball,
                   ball_floor_pair=names.index(f"{BALL}~{FLOOR_GEOM}"),
                   joint_dofs=one_hot(layout.joint_dof_adr, model.nv),
                   joint_actuators=one_hot(layout.actuator_ids, model.nu),
                   foot_pairs=(feet & floor).astype(np.float32), n_agents=layout.n_agents,
                   torso_bodies=one_hot(layout.torso_body, model.nbody))


PER_GAME = ("softness", "timeconst", "margin")
"""Quantities drawn once per game (the feet of one robot model), not per robot."""


OP3_RANDOMIZATION = SoccerRandomization(enabled=True, **OP3_COVERING)
"""The OP3 tasks' default randomisation for training: the earlier ranges and those covering the reference models."""


def sample(rng: jax.Array, config: SoccerRandomization, model: mujoco.MjModel, nominal_ball_mass: float,
           n_agents: int, n_joints: int, n_substeps: int) -> dict:
    """Randomisation parameters of one episode (nominal values when disabled); per-robot quantities have a leading
    agent axis ([n_agents], [n_agents, n_joints], ...)."""
    nb, nu = model.nbody, model.nu
    if not config.enabled:
        f = model.pair_friction
        return dict(floor=jnp.float32(np.max(f[:, 0])), ball=jnp.float32(f[0, 0]), rolling=jnp.float32(0.0),
                    ball_mass=jnp.float32(nominal_ball_mass), mass_scale=jnp.ones(nb), strength=jnp.ones(nu))
    k = jax.random.split(rng, 6)
    u = lambda key, r, shape=(): jax.random.uniform(key, shape, minval=r[0], maxval=r[1])
    dr = dict(floor=u(k[0], config.floor_friction), ball=u(k[1], config.ball_friction),
              rolling=u(k[2], config.ball_rolling_friction), ball_mass=u(k[3], config.ball_mass),
              mass_scale=u(k[4], config.link_mass_scale, (nb,)), strength=u(k[5], config.motor_strength, (nu,)))
    more = jax.random.split(jax.random.fold_in(rng, 1), n_agents + 2)
    body = jax.random.split(jax.random.fold_in(rng, 2), 2)
    if config.payload is not None:
        dr["payload"] = u(body[0], config.payload, (n_agents,))
    if config.com_offset:
        dr["com"] = u(body[1], (-config.com_offset, config.com_offset), (n_agents, 3))
    if config.kp_scale is not None:
        dr["kp"] = u(more[-2], config.kp_scale, (n_agents,))
    if config.kd_scale is not None:
        dr["kd"] = u(more[-1], config.kd_scale, (n_agents,))
    robots = jax.vmap(lambda key: draw_model(config, key, n_joints, model.opt.timestep, n_substeps))(more[:n_agents])
    dr.update({k: v[0] if k in PER_GAME else v for k, v in robots.items()})
    return dr


def robot_fields(base: dict, dr: dict, where: "SoccerDynamics", xp=jnp) -> dict:
    """The joint and foot-contact fields of the per-robot quantities in `dr` (legged.envs.randomize.model_fields)."""
    flat = lambda v: xp.reshape(v, xp.shape(v)[:-2] + (-1,))       # [..., A, J] -> [..., A * J]
    drawn = {k: flat(dr[k]) if k in ("damping", "armature", "frictionloss") else dr[k]
             for k in ("damping", "armature", "frictionloss") + PER_GAME if k in dr}
    if not drawn:
        return {}
    return model_fields(dict(base, joint_dofs=where.joint_dofs, foot_pairs=where.foot_pairs), drawn, xp)


def per_actuator(values, where: "SoccerDynamics", xp=jnp):
    """[..., nu] from per-joint values of every robot [..., A, J] (each to its joint's actuator)."""
    values = xp.asarray(values)
    return xp.reshape(values, xp.shape(values)[:-2] + (-1,)) @ where.joint_actuators


def randomized_fields(base: dict, dr: dict, where: SoccerDynamics, xp=jnp) -> dict:
    """The model fields of `FIELDS` after randomisation `dr` (rows of a leading batch axis allowed in numpy)."""
    mass0, inertia0 = base["body_mass"], base["body_inertia"]
    ball = np.arange(len(mass0)) == where.ball_body
    scale = xp.where(where.robot_bodies, dr["mass_scale"], 1.0)
    scale = xp.where(ball, (xp.asarray(dr["ball_mass"]) / mass0[where.ball_body])[..., None], scale)
    friction = base["pair_friction"]                    # [npair, 5]: slide, slide, torsion, roll, roll
    lead = scale.shape[:-1]
    f = xp.broadcast_to(friction, lead + friction.shape)
    slide = xp.where(where.ball_pairs, xp.asarray(dr["ball"])[..., None], xp.asarray(dr["floor"])[..., None])
    rolling = xp.asarray(dr["rolling"])[..., None]
    is_ball_floor = np.arange(len(friction)) == where.ball_floor_pair  # torsion and rolling of the ball on grass
    friction = xp.stack([slide, slide] + [xp.where(is_ball_floor, rolling, f[..., c]) for c in (2, 3, 4)], axis=-1)
    n_joints = where.joint_dofs.shape[0] // where.n_agents
    gains = {}
    for key in ("kp", "kd"):  # each robot's scale, on its actuators
        if key in dr:
            per_robot = xp.asarray(dr[key])[..., None] * xp.ones(n_joints)
            gains[key] = per_actuator(per_robot, where, xp)
    gain, bias = servo_fields(base, gains.get("kp", 1.0), gains.get("kd", 1.0), dr["strength"], xp)
    mass = mass0 * scale
    if "payload" in dr:  # each torso's added mass, its inertia scaled with it
        added = xp.asarray(dr["payload"]) @ where.torso_bodies                 # [..., nbody]
        scale = scale * xp.where(added != 0, (mass + added) / xp.where(mass > 0, mass, 1.0), 1.0)
        mass = mass + added
    out = dict(body_mass=mass, body_inertia=inertia0 * scale[..., None], pair_friction=friction,
               actuator_gainprm=gain, actuator_biasprm=bias)
    if "com" in dr:
        out["body_ipos"] = base["body_ipos"] + xp.swapaxes(xp.swapaxes(xp.asarray(dr["com"]), -1, -2)
                                                           @ where.torso_bodies, -1, -2)
    out.update(robot_fields(base, dr, where, xp))
    return out
