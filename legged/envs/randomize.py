"""Domain randomisation of the Go1 tasks as pure functions: `draw` samples an episode's parameters from a
RandomizationConfig and a key, `randomized_fields` turns them into model fields, one function for both engines
(jax.numpy for MJX models under vmap, numpy for the native engine's per-simulation fields).

Parameters a config leaves unset (None, 0) are not drawn, so runs saved before they existed replay their episodes
unchanged; their keys come from a separate stream (`fold_in(rng, 1)`) for the same reason.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import mujoco

from legged.envs.config import SOFT_SOLIMP, RandomizationConfig

MUJOCO_SOLIMP = (0.9, 0.95, 0.001, 0.5, 2.0)
"""MuJoCo's default solimp: the hard end of RandomizationConfig.contact_softness."""
MODEL_DR = ("damping", "armature", "frictionloss", "softness", "timeconst", "margin", "latency", "spin")
"""Randomised model quantities a teacher's privileged observation holds after the older ones (where drawn)."""
CONE_DR = ("elliptic", "impratio")
"""The solver's friction-cone draws (RandomizationConfig.elliptic_share, impratio): a privileged part of their own,
after MODEL_DR's, so that a warm start keeps the critic's weights of the older quantities."""


def draw(c: RandomizationConfig, rng: jax.Array, nbody: int, nu: int, sim_dt: float, n_substeps: int,
         nominal_friction) -> dict:
    """An episode's randomisation parameters (nominal values when `c` is disabled): per-body mass scales, payload,
    centre of mass, per-motor strength, Kp and Kd scales, friction, and where set the joints' damping, armature and
    friction loss, the feet's contact softness, time constant and margin, the action latency in whole physics steps
    (of `sim_dt`, at most `n_substeps`), encoder offsets and IMU biases."""
    if not c.enabled:
        return dict(friction=jnp.float32(nominal_friction), mass_scale=jnp.ones(nbody), base_mass=jnp.float32(0.0),
                    com=jnp.zeros(3), strength=jnp.ones(nu), kp=jnp.float32(1.0), kd=jnp.float32(1.0))
    k = jax.random.split(rng, 7)
    u = lambda key, r, shape=(): jax.random.uniform(key, shape, minval=r[0], maxval=r[1])
    dr = dict(friction=u(k[0], c.friction), mass_scale=u(k[1], c.link_mass_scale, (nbody,)),
              base_mass=u(k[2], c.base_mass_offset), com=u(k[3], (-c.com_offset, c.com_offset), (3,)),
              strength=u(k[4], c.motor_strength, (nu,)), kp=u(k[5], c.kp_scale), kd=u(k[6], c.kd_scale))
    return dict(dr, **draw_model(c, jax.random.fold_in(rng, 1), nu, sim_dt, n_substeps))


def draw_model(c, rng: jax.Array, nu: int, sim_dt: float, n_substeps: int) -> dict:
    """The model quantities of one robot that `c` (a RandomizationConfig or a SoccerRandomization) sets, drawn from
    `rng`: its `nu` joints' damping, armature and friction loss (each joint on its own, or with `joint_spread` one
    value per robot spread over its joints), its feet's contact softness, time constant and
    margin, the action latency in whole physics steps (of `sim_dt`, at most `n_substeps`), encoder offsets and IMU
    biases (the quantities left unset, None or 0, are not drawn)."""
    dr = {}
    more = jax.random.split(rng, 9)
    u = lambda key, r, shape=(): jax.random.uniform(key, shape, minval=r[0], maxval=r[1])
    ranges = (("damping", c.joint_damping, (nu,)), ("armature", c.joint_armature, (nu,)),
              ("frictionloss", c.joint_frictionloss, (nu,)), ("softness", c.contact_softness, ()),
              ("timeconst", c.contact_timeconst, ()), ("margin", c.contact_margin, ()))
    spread = getattr(c, "joint_spread", None)
    for i, (key, r, shape) in enumerate(ranges):
        if r is None:
            continue
        if spread is not None and shape:  # one value per robot, spread over its joints
            common, factor = jax.random.split(more[i])
            value = u(common, r) * (1.0 + spread * jax.random.uniform(factor, shape, minval=-1.0, maxval=1.0))
            dr[key] = jnp.clip(value, r[0], r[1])
        else:
            dr[key] = u(more[i], r, shape)
    if getattr(c, "contact_spin", None) is not None:  # its own key: the others draw what they drew before it
        dr["spin"] = u(jax.random.fold_in(rng, 2), c.contact_spin)
    if getattr(c, "elliptic_share", None) is not None:  # own keys as the spin's
        dr["elliptic"] = (jax.random.uniform(jax.random.fold_in(rng, 3)) < c.elliptic_share).astype(jnp.float32)
    if getattr(c, "impratio", None) is not None:  # log-uniform: as many robots between 1 and 10 as between 10 and 100
        dr["impratio"] = jnp.exp(u(jax.random.fold_in(rng, 4), tuple(math.log(r) for r in c.impratio)))
    if c.latency_s is not None:
        low, high = (min(int(round(t / sim_dt)), n_substeps) for t in c.latency_s)
        dr["latency"] = jax.random.randint(more[6], (), low, high + 1)
    if c.encoder_offset:
        dr["encoder_offset"] = u(more[7], (-c.encoder_offset, c.encoder_offset), (nu,))
    if any(c.imu_bias):
        bias = jax.random.uniform(more[8], (6,), minval=-1.0, maxval=1.0)
        dr["gravity_bias"], dr["gyro_bias"] = bias[:3] * c.imu_bias[0], bias[3:] * c.imu_bias[1]
    return dr


def nominal_draw(base: dict, nominal_friction, impratio: float) -> dict:
    """The parameters `draw` gives the nominal robot of a model's nominal fields `base` (as LeggedEnv holds them),
    for every quantity it may draw: the model's own friction, joint damping, armature, friction loss, feet's solref
    time constant and margin and impratio; unit scales; no payload, offsets, biases or latency; MuJoCo's default
    contact impedance (softness 0) and the model's own friction cone."""
    dofs, feet = base["joint_dofs"], np.flatnonzero(np.asarray(base["foot_pairs"]) > 0)
    nu, nbody = dofs.shape[0], base["body_mass"].shape[0]
    out = dict(friction=jnp.float32(nominal_friction), mass_scale=jnp.ones(nbody), base_mass=jnp.float32(0.0),
               com=jnp.zeros(3), strength=jnp.ones(nu), kp=jnp.float32(1.0), kd=jnp.float32(1.0),
               damping=dofs @ base["dof_damping"], armature=dofs @ base["dof_armature"],
               frictionloss=dofs @ base["dof_frictionloss"], softness=jnp.float32(0.0), latency=jnp.int32(0),
               spin=jnp.float32(1.0), elliptic=jnp.float32(0.0), impratio=jnp.float32(impratio),
               encoder_offset=jnp.zeros(nu), gravity_bias=jnp.zeros(3), gyro_bias=jnp.zeros(3))
    if len(feet):
        out.update(timeconst=base["pair_solref"][feet[0], 0], margin=base["pair_margin"][feet[0]])
    return out


def weakened(dr: dict, nominal: dict, scale) -> dict:
    """A draw `dr` moved toward the nominal robot's parameters `nominal_draw`: each quantity at `scale` (0-1) of its
    way from the nominal value to the drawn one (0: the nominal robot, 1: the draw). The latency, in whole physics
    steps, and the elliptic cone, on or off, are rounded."""
    out = {}
    for key, value in dr.items():
        moved = nominal[key] + scale * (value - nominal[key])
        out[key] = jnp.round(moved).astype(jnp.asarray(value).dtype) if key in ("latency", "elliptic") else moved
    return out


def late_controls(previous, targets, latency, n_substeps: int):
    """One control step's controls under action latency, a schedule (n_substeps, nu): the previous step's targets for
    the first `latency` physics steps (a scalar, or one per actuator), this step's after. The one rule of every
    environment: a latency of a whole control period delays each action by exactly one step."""
    return jnp.where(jnp.arange(n_substeps)[:, None] < latency, previous, targets)


def check_latency(latency_s, sim_dt: float, ctrl_dt: float) -> None:
    """A latency range longer than one control period is an error naming the field (the draws would be clipped to
    one period without a word)."""
    if latency_s is not None and round(max(latency_s) / sim_dt) > round(ctrl_dt / sim_dt):
        raise ValueError(f"env.randomization.latency_s: {max(latency_s)} s is more than one control period "
                         f"({ctrl_dt} s); action latency is modelled up to one period (a one-step delay)")


def randomized_fields(base: dict, dr: dict, trunk: int, xp=jnp) -> dict:
    """Model fields after applying randomisation parameters `dr` to the nominal fields `base`.

    One function for both engines: jax.numpy for MJX models (per environment, under vmap) and numpy for
    native ones, where `dr` may carry a leading batch axis (one row per simulation).
    """
    scale = dr["mass_scale"]                                       # [..., nbody]
    is_trunk = xp.arange(scale.shape[-1]) == trunk
    mass = base["body_mass"] * scale
    mass_trunk = mass[..., trunk] + dr["base_mass"]
    ratio = xp.where(is_trunk, (mass_trunk / mass[..., trunk])[..., None], 1.0)
    inertia = base["body_inertia"] * (scale * ratio)[..., None]
    mass = xp.where(is_trunk, mass_trunk[..., None], mass)
    ipos = base["body_ipos"] + is_trunk[:, None] * xp.asarray(dr["com"])[..., None, :]
    pairs = base["pair_friction"]
    spin = pairs[:, 2:]                                            # torsional, rolling: the feet's scaled (condim 6)
    if "spin" in dr:
        spin = spin * xp.where(base["foot_pairs"][:, None] > 0, xp.asarray(dr["spin"])[..., None, None], 1.0)
    friction = xp.concatenate([xp.broadcast_to(xp.asarray(dr["friction"])[..., None, None], mass.shape[:-1] + (len(pairs), 2)),
                               xp.broadcast_to(spin, mass.shape[:-1] + pairs[:, 2:].shape)], axis=-1)
    gain, bias = servo_fields(base, xp.asarray(dr["kp"])[..., None], xp.asarray(dr["kd"])[..., None], dr["strength"], xp)
    out = dict(body_mass=mass, body_inertia=inertia, body_ipos=ipos, pair_friction=friction,
               actuator_gainprm=gain, actuator_biasprm=bias)
    out.update(model_fields(base, dr, xp))
    return out


def servo_fields(base: dict, kp, kd, strength, xp=jnp) -> tuple:
    """actuator_gainprm and actuator_biasprm of PD position servos whose proportional gains are scaled by `kp *
    strength` and derivative gains by `kd * strength` (each broadcast against the actuators, [..., nu])."""
    gain0, bias0 = base["actuator_gainprm"], base["actuator_biasprm"]
    kp_gain = gain0[:, 0] * kp * strength                          # [..., nu]
    lead = xp.shape(kp_gain)[:-1]
    keep = lambda a, cols: xp.broadcast_to(a[:, cols], lead + a[:, cols].shape)
    gain = xp.concatenate([kp_gain[..., None], keep(gain0, slice(1, None))], axis=-1)
    bias = xp.concatenate([keep(bias0, slice(0, 1)), (bias0[:, 1] * kp * strength)[..., None],
                           (bias0[:, 2] * kd * strength)[..., None], keep(bias0, slice(3, None))], axis=-1)
    return gain, bias


def model_fields(base: dict, dr: dict, xp=jnp) -> dict:
    """The joint and foot-contact fields of the quantities `draw_model` drew: dof damping, armature and friction
    loss of the drawn joints (`base["joint_dofs"]`: one-hot [nu, nv] from a drawn joint to its dof), the feet's
    pairs' (`base["foot_pairs"]`) solimp, solref and margin."""
    out = {}
    dofs = base["joint_dofs"]
    for key, field in (("damping", "dof_damping"), ("armature", "dof_armature"), ("frictionloss", "dof_frictionloss")):
        if key in dr:
            out[field] = xp.where(dofs.sum(0) > 0, xp.asarray(dr[key]) @ dofs, base[field])
    feet = base["foot_pairs"][:, None] > 0                         # [npair, 1]
    if "softness" in dr:
        soft = xp.asarray(dr["softness"])[..., None, None]
        default, target = xp.asarray(MUJOCO_SOLIMP), xp.asarray(SOFT_SOLIMP)
        out["pair_solimp"] = xp.where(feet, (1 - soft) * default + soft * target, base["pair_solimp"])
    if "timeconst" in dr:
        solref = base["pair_solref"]
        timeconst = xp.asarray(dr["timeconst"])[..., None, None]
        lead = xp.shape(timeconst)[:-2]
        rest = xp.broadcast_to(solref[:, 1:], lead + solref[:, 1:].shape)
        timeconst = xp.broadcast_to(timeconst, lead + solref[:, :1].shape)
        out["pair_solref"] = xp.where(feet, xp.concatenate([timeconst, rest], -1), solref)
    if "margin" in dr:
        out["pair_margin"] = xp.where(feet[:, 0], xp.asarray(dr["margin"])[..., None], base["pair_margin"])
    if "impratio" in dr:
        out["opt.impratio"] = xp.asarray(dr["impratio"])
    if "elliptic" in dr:  # the model's cone where not drawn elliptic (an MJX model keeps its own: see `mjx_fields`)
        elliptic = int(mujoco.mjtCone.mjCONE_ELLIPTIC)
        out["opt.cone"] = xp.where(xp.asarray(dr["elliptic"]) > 0, elliptic, base["cone"]).astype(xp.int32)
    return out


def mjx_fields(model, fields: dict) -> dict:
    """`randomized_fields` as arguments of an MJX model's `replace`: the solver options (`opt.<name>`) inside its
    `opt`, less the friction cone, which MJX compiles into its programs (one cone for every environment)."""
    fields = dict(fields)
    options = {k[4:]: fields.pop(k) for k in [k for k in fields if k.startswith("opt.")]}
    options.pop("cone", None)
    return dict(fields, opt=model.opt.replace(**options)) if options else fields
