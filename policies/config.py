"""Training configuration: frozen dataclasses, YAML round trip and `--set path.to.field=value` overrides."""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Literal

import yaml

from legged.soccer.config import SoccerConfig
from legged.tasks import default_config, task_entry
from policies.config_io import ConfigError, from_dict, to_dict
from policies.soccer.config import SoccerTrainConfig, check_soccer, nest_soccer_keys, soccer_override_path


@dataclasses.dataclass(frozen=True)
class PPOConfig:
    """PPO hyper-parameters (the usual legged-locomotion PPO defaults), shared by both backends where they apply."""

    learning_rate: float = 1e-3
    """Adam step size (adapted by the KL schedule in rsl-rl)."""
    num_steps_per_env: int = 24
    """Rollout length per environment per iteration."""
    num_learning_epochs: int = 5
    """Passes over each rollout."""
    num_mini_batches: int = 4
    """Mini-batches per pass."""
    clip_param: float = 0.2
    """PPO ratio clip."""
    gamma: float = 0.99
    """Discount."""
    lam: float = 0.95
    """GAE lambda."""
    entropy_coef: float = 0.01
    """Entropy bonus weight."""
    value_loss_coef: float = 1.0
    """Value-loss weight."""
    desired_kl: float = 0.01
    """Target KL of the adaptive learning-rate schedule."""
    schedule: Literal["adaptive", "fixed"] = "adaptive"
    """rsl backend: adapt the learning rate to `desired_kl` after every mini-batch, or keep it fixed."""
    max_grad_norm: float = 1.0
    """Gradient clipping norm."""
    mixed_precision: bool = False
    """rsl backend: run the update's forward passes and losses in bfloat16 (torch autocast; rsl-rl's
    use_mixed_precision), which CPUs with bf16 matrix units (AMX, AVX512-BF16) multiply several times faster; it
    learned go1-flat more slowly per step than float32 (docs/training.md)."""
    actor_hidden: tuple[int, ...] = (512, 256, 128)
    """Actor MLP layer sizes (reads `state`)."""
    critic_hidden: tuple[int, ...] = (512, 256, 128)
    """Critic MLP layer sizes (reads `privileged_state`)."""
    activation: str = "elu"
    """Hidden activation."""
    init_noise_std: float = 1.0
    """Initial standard deviation of the Gaussian policy."""
    zero_action_init: bool = False
    """Start the actor's output layer at zero (rsl backend), so a residual skill first plays its reference."""
    obs_normalization: bool = True
    """Running mean/std normalisation of observations (rsl-rl backend; Brax PPO always normalises)."""
    obs_std_floor: float = 0.01
    """Brax backend: least std an observation is divided by (a rare contact force / 1e-6 made the value diverge)."""


@dataclasses.dataclass(frozen=True)
class LatentConfig:
    """Latent-variable actors (policies.latent_models): the teacher's privileged encoder, the students' history
    encoders, and HIB's information bottleneck (policies.hib)."""

    history_steps: int = 25
    """Steps of `state` history the students read (0.5 s at 50 Hz, about one trot cycle); copied into the env's
    `history_steps`."""
    latent_dim: int = 16
    """Size of the latent z (the teacher's z_p and the students' z)."""
    encoder_hidden: tuple[int, ...] = (256, 128)
    """MLP layer sizes of the encoders of the privileged state (and of the history with history_encoder=mlp)."""
    history_encoder: Literal["conv", "mlp"] = "conv"
    """Encoder of the `history` group, for every algorithm that reads it: conv (RMA's: each step embedded, then
    1-D convolutions over time; policies.latent_models.HistoryConv) or mlp (on the flattened history)."""
    kl_weight: float = 1e-2
    """HIB's alpha: weight of KL(q(z|h) || N(0, I)), the upper bound of I(H; Z) (summed over z's dimensions; at
    1e-3 it did not bind: the KL rose to 53 nats within 7 iterations, z's standard deviation to about 0.05)."""
    infonce_weight: float = 1.0
    """Weight of the InfoNCE loss, whose negative is the lower bound of I(Z; S^p)."""
    temperature: float = 0.1
    """InfoNCE temperature (cosine similarities of projected z and privileged embeddings)."""
    projection_dim: int = 32
    """Size of the InfoNCE projections of z and of the privileged state."""
    infonce_samples: int = 512
    """Anchors per mini-batch for InfoNCE (a random subset: the score matrix is this squared)."""


@dataclasses.dataclass(frozen=True)
class DistillConfig:
    """Distillation from a teacher run (`legged distill`)."""

    teacher: str = ""
    """The teacher's run directory (trained with --algo teacher)."""
    learning_rate: float = 1e-3
    """Adam step size of the student."""
    num_learning_epochs: int = 5
    """Passes over each rollout (5, as PPO's: 20 gradient steps per rollout of 24 steps, with gradient_length 6)."""
    gradient_length: int = 6
    """Rollout steps whose losses are summed per gradient step (6 x 1,024 environments = PPO's mini-batch)."""
    student_noise_std: float = 0.1
    """dagger: standard deviation of the student's exploration noise while it acts."""
    kl_weight: float = 1.0
    """kl: initial weight of KL(teacher || student) added to the student's PPO loss (policies.teacher_kl)."""
    kl_decay: float = 0.995
    """kl: factor applied to that weight after every iteration."""
    critic_warmup: int = 0
    """kl: first iterations in which only the critic learns (the actor frozen), so that PPO's first advantages
    come from a trained value function (for a student started from an earlier one, distill.student_init)."""
    student_memory: int = 0
    """dagger and kl vision students: size of a GRU memory between features and head (0: none;
    policies.memory_models)."""
    student_init: str = ""
    """dagger and kl vision students: an earlier dagger vision student (its run directory's newest checkpoint, or
    a checkpoint file in it) whose camera encoder and normaliser this one starts from."""
    student_init_whole: bool = False
    """With student_init: start from that student whole (encoder, memory, head, normaliser, noise), which must
    fit this one, e.g. the second stage of a curriculum (the empty-goal drill first, then the game)."""
    teacher_act_fraction: float = 0.0
    """dagger: share of the environments the teacher acts in at first (DAgger's beta; the student learns on all)."""
    teacher_act_iterations: int = 0
    """dagger: iterations over which `teacher_act_fraction` falls linearly to 0 (0: it stays)."""
    label_weights: dict[str, float] = dataclasses.field(default_factory=dict)
    """dagger students that estimate the game (soccer.command_prior=placo): weights of named groups of their labels in
    the behaviour loss (`corrections`, `ball`, `ball_vel`, `own_goal`, `opponent_goal`, `teammate0`,
    `opponent0`, ...; groups not listed weigh 1, but the opponents weigh 0 in the empty-goal drill, which has
    none). A mapping: this config is not hashable."""
    correction_margin: float = math.inf
    """Students that estimate the game: their corrections' labels are the teacher's command clipped to [-1 - this,
    1 + this] less the placo command at the truth (inf: the raw corrections; 0: as the walker clips)."""
    teacher_prior: bool = False
    """Set by `legged distill`: the teacher (a state soccer player, soccer.command_prior=placo) corrected the placo
    player's command (see TrainConfig.game_gives_placo_command for what the vision student's game makes of it)."""


ALGOS = ("ppo", "teacher", "hib", "hib-no-ib", "history", "dagger", "rma", "kl")
"""Training algorithms: `legged train --algo` takes the first five, `legged distill --method` the last three."""
DISTILL_ALGOS = ("dagger", "rma", "kl")
"""Algorithms that learn from a teacher run (`distill.teacher`)."""

HISTORY_ALGOS = ("hib", "hib-no-ib", "history", "dagger", "rma")
"""Algorithms whose actor reads the `history` observation."""


@dataclasses.dataclass(frozen=True)
class TrainConfig:
    """One training run."""

    task: str
    """Registered task name (`legged tasks`)."""
    backend: Literal["rsl", "brax"] = "rsl"
    """rsl: rsl-rl PPO in PyTorch; brax: Brax PPO in JAX."""
    num_envs: int = 256
    """Parallel environments."""
    timesteps: int = 1_000_000
    """Environment steps to train for (all environments together)."""
    seed: int = 0
    """Seed of environments and networks."""
    checkpoint_every: int = 10
    """Iterations between checkpoints (the last one is always written)."""
    random_episode_start: bool = False
    """rsl backend: whenever training starts or resumes, each environment's episode clock starts at a random step
    of its time limit (rsl-rl's init_at_random_ep_len), so that episodes end on different iterations instead of
    all together (e.g. 512 soccer games of 60 s) and every rollout holds every phase of an episode."""
    randomization_ramp: int = 0
    """rsl backend: environment steps over which the domain randomisation (env.randomization, pushes included) of new
    episodes grows from none, the nominal robot, to the task's full ranges, each drawn quantity moving linearly from
    its nominal value to its draw (0: the full ranges from the first episode). Evaluation always draws the full
    ranges."""
    randomization_curriculum: float = 0.0
    """rsl backend: a randomisation scale per environment, from 0 (the nominal robot) to 1 (the task's full ranges),
    that starts at 0 and moves by this step after each episode: up after one the task counts as mastered (go1 tracking:
    ran its time limit with a mean velocity error under half the command plus 5 cm/s), down after a fall (0: off;
    exclusive with randomization_ramp). Evaluation always draws the full ranges."""
    device: str = "cpu"
    """PyTorch device of the rsl backend (cpu, cuda, cuda:1, ...)."""
    physics: Literal["mjx", "native"] = "mjx"
    """Physics engine: mjx (JAX; fastest on an accelerator) or native (MuJoCo's C engine; fastest on a CPU)."""
    threads: int = 0
    """CPU threads of native physics and of torch (0: every core this process may use)."""
    init_from: str = ""
    """Run directory whose latest networks start this run (rsl backend; policies.warm_start), or '' for none."""
    algo: Literal["ppo", "teacher", "hib", "hib-no-ib", "history", "dagger", "rma", "kl"] = "ppo"
    """ppo: actor on `state`; teacher: actor on `state` and an encoding of `privileged_state`; hib, hib-no-ib,
    history: one-stage students on the state history; dagger, rma: students distilled from `distill.teacher`."""
    ppo: PPOConfig = PPOConfig()
    """PPO hyper-parameters."""
    latent: LatentConfig = LatentConfig()
    """Encoders and the information bottleneck (teacher and student algorithms)."""
    distill: DistillConfig = DistillConfig()
    """Distillation settings (dagger, rma)."""
    env: Any = None
    """The task's environment config (filled in from the task's defaults)."""
    soccer: SoccerTrainConfig = SoccerTrainConfig()
    """Soccer tasks only: the skills the player commands (walker, command_prior, getup), its opponents (selfplay),
    a drill to train on, a vision student's pilot, a pilot's student (policies.soccer.config)."""

    @property
    def estimates_world(self) -> bool:
        """Whether this vision soccer player adds the placo command (soccer.command_prior) to its own, computed from its
        estimate of the game features, which its actions then hold (legged.soccer.learner)."""
        return bool(self.soccer.command_prior) and bool(getattr(self.env, "vision", False))

    @property
    def game_gives_placo_command(self) -> bool:
        """Whether this vision student's game computes the placo command at the true state (LearnerView's
        `teacher_prior`): as the observation `command_prior` of a student whose teacher corrected that command
        (distill.teacher_prior), or, for a student that estimates the game (estimates_world, which computes the
        command itself from its estimate), only to clip its correction labels (finite distill.correction_margin)."""
        if self.estimates_world:
            return math.isfinite(self.distill.correction_margin)
        return bool(self.distill.teacher_prior)

    @property
    def self_play(self) -> bool:
        """Whether this run trains against snapshots of itself (soccer games, rsl backend, state observations)."""
        entry = task_entry(self.task)
        if entry.kind != "soccer" or self.soccer.selfplay.opponent == "scripted" or self.soccer.drill:
            return False
        return self.backend == "rsl" and not entry.vision

    def resolved(self) -> "TrainConfig":
        """This config with the task's default env config filled in and values checked."""
        cfg = self if self.env is not None else dataclasses.replace(self, env=default_config(self.task))
        if cfg.backend not in ("rsl", "brax"):
            raise ConfigError(f"backend must be 'rsl' or 'brax', got {cfg.backend!r}")
        if cfg.physics not in ("mjx", "native"):
            raise ConfigError(f"physics must be 'mjx' or 'native', got {cfg.physics!r}")
        entry = task_entry(cfg.task)
        try:
            entry.check(cfg.physics, cfg.backend)
        except ValueError as exc:
            raise ConfigError(str(exc)) from None
        if cfg.backend == "brax" and cfg.physics == "native":
            raise ConfigError("--backend brax needs --physics mjx (Brax PPO compiles the environment into its "
                              "training step); train native physics with --backend rsl")
        if cfg.backend == "brax" and cfg.random_episode_start:
            raise ConfigError("random_episode_start is for --backend rsl (Brax PPO resets its environments itself)")
        if cfg.randomization_ramp < 0:
            raise ConfigError(f"randomization_ramp must be >= 0 environment steps (0: none), got "
                              f"{cfg.randomization_ramp}")
        if not 0.0 <= cfg.randomization_curriculum <= 1.0:
            raise ConfigError(f"randomization_curriculum is a step of the randomisation scale in [0, 1] (0: off), got "
                              f"{cfg.randomization_curriculum}")
        if cfg.randomization_curriculum and cfg.randomization_ramp:
            raise ConfigError("randomization_ramp and randomization_curriculum both set the randomisation's scale: "
                              "choose one (a task's recipe may set the curriculum: add --set "
                              "randomization_curriculum=0 to use the ramp)")
        if (cfg.randomization_ramp or cfg.randomization_curriculum) and cfg.backend != "rsl":
            raise ConfigError("randomization_ramp and randomization_curriculum are for --backend rsl (Brax PPO resets "
                              "its environments itself)")
        if (cfg.randomization_ramp or cfg.randomization_curriculum) and isinstance(cfg.env, SoccerConfig):
            raise ConfigError(f"randomization_ramp and randomization_curriculum are for the Go1 tasks; {cfg.task} "
                              "draws its robots' randomisation in its game (soccer.env)")
        if cfg.backend == "brax" and cfg.ppo.mixed_precision:
            raise ConfigError("ppo.mixed_precision is for --backend rsl (rsl-rl's bfloat16 update); Brax trains in "
                              "float32")
        if cfg.threads < 0:
            raise ConfigError(f"threads must be >= 1 (or 0 for every core), got {cfg.threads}")
        for name in ("num_envs", "timesteps", "checkpoint_every"):
            if getattr(cfg, name) < 1:
                raise ConfigError(f"{name} must be >= 1, got {getattr(cfg, name)}")
        check_soccer(cfg, entry)
        _check_ppo(cfg.ppo)
        cfg = _check_algo(cfg, entry)
        if cfg.backend == "brax" and getattr(cfg.env, "curriculum", False):
            raise ConfigError("the confined curriculum needs the rsl backend (Brax PPO's resets cannot hand an "
                              "episode's level to the next); add --set env.curriculum=false for --backend brax")
        if cfg.ppo.zero_action_init and cfg.backend != "rsl":
            raise ConfigError("ppo.zero_action_init needs the rsl backend")
        if cfg.init_from and cfg.backend != "rsl":
            raise ConfigError("init_from (a warm start) needs the rsl backend")
        if cfg.num_envs > 2**20 or cfg.timesteps > 10**12:
            raise ConfigError(f"num_envs ({cfg.num_envs}) must be at most {2**20:,} and timesteps ({cfg.timesteps}) "
                              f"at most {10**12:,}")
        if cfg.num_envs * cfg.ppo.num_steps_per_env % cfg.ppo.num_mini_batches:
            raise ConfigError(f"num_envs x num_steps_per_env ({cfg.num_envs} x {cfg.ppo.num_steps_per_env}) must "
                              f"divide into num_mini_batches ({cfg.ppo.num_mini_batches})")
        return cfg


def _check_algo(cfg: TrainConfig, entry) -> TrainConfig:
    """ConfigError for an algorithm the run cannot use; the config with the env's history length set."""
    if cfg.algo not in ALGOS:
        raise ConfigError(f"algo must be one of {', '.join(ALGOS)}, got {cfg.algo!r}")
    d, vision_soccer = cfg.distill, entry.kind == "soccer" and entry.vision and cfg.backend == "rsl"
    if (d.student_memory or d.student_init) and not (cfg.algo in ("dagger", "kl") and vision_soccer):
        raise ConfigError(f"distill.student_memory and distill.student_init are for dagger and kl vision students "
                          f"(legged distill ... --task soccer-1v1-vision --method dagger|kl), not --algo {cfg.algo} "
                          f"on {cfg.task}")
    if d.critic_warmup and cfg.algo != "kl":
        raise ConfigError(f"distill.critic_warmup (iterations in which only PPO's critic learns) is for --method kl, "
                          f"not {cfg.algo}")
    if d.teacher_act_fraction and cfg.algo != "dagger":
        raise ConfigError(f"distill.teacher_act_fraction (DAgger's beta) is for --method dagger, not {cfg.algo}")
    if cfg.algo == "ppo":
        return cfg
    if cfg.init_from:
        raise ConfigError(f"init_from (a warm start) works with --algo ppo only, not {cfg.algo}")
    if cfg.algo in DISTILL_ALGOS and not cfg.distill.teacher:
        raise ConfigError(f"--algo {cfg.algo} distils a teacher: use `legged distill TEACHER_RUN --method {cfg.algo}`")
    if cfg.algo in ("dagger", "kl") and vision_soccer:
        _check_distill(cfg.distill)  # a camera student of a state soccer player (policies.distill)
        if cfg.algo == "kl" and d.student_memory and cfg.num_envs % cfg.ppo.num_mini_batches:
            raise ConfigError(f"a kl student with memory learns from whole trajectories, num_envs / "
                              f"ppo.num_mini_batches environments at a time: num_envs ({cfg.num_envs}) must be a "
                              f"multiple of ppo.num_mini_batches ({cfg.ppo.num_mini_batches})")
        return cfg
    if cfg.algo == "kl":
        raise ConfigError(f"--method kl distils a state soccer player into its vision task (--task "
                          f"soccer-1v1-vision), not into {cfg.task}")
    if cfg.backend != "rsl" or entry.vision or entry.kind == "soccer":
        raise ConfigError(f"--algo {cfg.algo} needs the rsl backend and a single-robot state task (not {cfg.task} "
                          f"with backend {cfg.backend})")
    lat = cfg.latent
    if cfg.algo in HISTORY_ALGOS and lat.history_steps < 1:
        raise ConfigError(f"latent.history_steps must be >= 1 for --algo {cfg.algo}, got {lat.history_steps}")
    rules = [("latent_dim", 1 <= lat.latent_dim <= 4096), ("kl_weight", 0 <= lat.kl_weight <= 1e3),
             ("infonce_weight", 0 <= lat.infonce_weight <= 1e3), ("temperature", 0 < lat.temperature <= 100),
             ("projection_dim", 1 <= lat.projection_dim <= 4096), ("infonce_samples", 2 <= lat.infonce_samples),
             ("encoder_hidden", len(lat.encoder_hidden) >= 1 and all(1 <= n <= 65536 for n in lat.encoder_hidden))]
    for name, ok in rules:
        if not ok:
            raise ConfigError(f"latent.{name} is out of range: {getattr(lat, name)!r}")
    _check_distill(cfg.distill)
    history = lat.history_steps if cfg.algo in HISTORY_ALGOS else 0
    if getattr(cfg.env, "history_steps", None) is None:
        raise ConfigError(f"--algo {cfg.algo} needs a legged task with a state history; {cfg.task} has none")
    return dataclasses.replace(cfg, env=dataclasses.replace(cfg.env, history_steps=history))


def _check_distill(d: DistillConfig) -> None:
    """ConfigError naming the distillation settings outside their ranges."""
    if not (0 < d.learning_rate <= 1 and d.num_learning_epochs >= 1 and d.gradient_length >= 1
            and 0 < d.student_noise_std <= 10 and 0 <= d.kl_weight <= 1e3 and 0 < d.kl_decay <= 1
            and 0 <= d.student_memory <= 4096 and 0 <= d.teacher_act_fraction <= 1 and d.teacher_act_iterations >= 0
            and d.correction_margin >= 0 and d.critic_warmup >= 0):
        raise ConfigError(f"distill: learning_rate in (0, 1], num_learning_epochs and gradient_length >= 1, "
                          f"student_noise_std in (0, 10], kl_weight in [0, 1000], kl_decay in (0, 1], student_memory "
                          f"in [0, 4096], teacher_act_fraction in [0, 1], teacher_act_iterations >= 0, "
                          f"correction_margin >= 0, critic_warmup >= 0; got {d}")
    if d.student_init_whole and not d.student_init:
        raise ConfigError("distill.student_init_whole takes the whole student of distill.student_init: name that run")


def _check_ppo(ppo: PPOConfig) -> None:
    """ConfigError naming the first PPO setting outside its range."""
    rules = [
        ("learning_rate", 0.0 < ppo.learning_rate <= 1.0, "in (0, 1]"),
        ("num_steps_per_env", 1 <= ppo.num_steps_per_env <= 100_000, "from 1 to 100,000"),
        ("num_learning_epochs", 1 <= ppo.num_learning_epochs <= 1000, "from 1 to 1,000"),
        ("num_mini_batches", 1 <= ppo.num_mini_batches <= 100_000, "from 1 to 100,000"),
        ("clip_param", 0.0 < ppo.clip_param <= 10.0, "in (0, 10]"),
        ("gamma", 0.0 < ppo.gamma <= 1.0, "in (0, 1]"),
        ("lam", 0.0 <= ppo.lam <= 1.0, "in [0, 1]"),
        ("entropy_coef", 0.0 <= ppo.entropy_coef <= 100.0, "in [0, 100]"),
        ("value_loss_coef", 0.0 < ppo.value_loss_coef <= 1000.0, "in (0, 1000]"),
        ("desired_kl", 0.0 < ppo.desired_kl <= 10.0, "in (0, 10]"),
        ("max_grad_norm", 0.0 < ppo.max_grad_norm <= 1e6, "in (0, 1e6]"),
        ("init_noise_std", 0.0 < ppo.init_noise_std <= 100.0, "in (0, 100]"),
        ("obs_std_floor", 0.0 < ppo.obs_std_floor <= 1e3, "in (0, 1000]"),
        ("actor_hidden", len(ppo.actor_hidden) >= 1 and all(1 <= n <= 65536 for n in ppo.actor_hidden),
         "one or more layer sizes from 1 to 65,536"),
        ("critic_hidden", len(ppo.critic_hidden) >= 1 and all(1 <= n <= 65536 for n in ppo.critic_hidden),
         "one or more layer sizes from 1 to 65,536"),
    ]
    for name, ok, allowed in rules:
        if not ok:
            raise ConfigError(f"ppo.{name} must be {allowed}, got {getattr(ppo, name)!r}")


MAPPINGS = ("distill.label_weights",)
"""Config fields that are mappings: `--set distill.label_weights.ball=4` sets one entry."""


def apply_overrides(config: TrainConfig, overrides: list[str]) -> TrainConfig:
    """Apply `a.b.c=value` overrides (e.g. `ppo.learning_rate=3e-4`, `env.episode_seconds=10`); the paths of the
    soccer settings from before TrainConfig.soccer (`walker=RUN`, `selfplay.scripted_fraction=0.7`) still work."""
    data = to_dict(config)
    for item in overrides:
        if "=" not in item:
            raise ConfigError(f"override {item!r} must look like path.to.field=value")
        path, text = item.split("=", 1)
        node, keys = data, soccer_override_path(path).split(".")
        for key in keys[:-1]:
            if not isinstance(node.get(key), dict):
                raise ConfigError(f"override {item!r}: {key!r} is not a config section")
            node = node[key]
        if keys[-1] not in node and ".".join(keys[:-1]) not in MAPPINGS:  # a mapping takes new keys
            raise ConfigError(f"override {item!r}: no field {keys[-1]!r} (fields: {', '.join(sorted(node))})")
        node[keys[-1]] = yaml.safe_load(text) if text else text
    return load_config(data)


def load_config(data: dict) -> TrainConfig:
    """TrainConfig from its `to_dict` form (as stored in a run's config.yaml; one written before TrainConfig.soccer,
    with the soccer settings at the top level, is read with them moved there)."""
    if not isinstance(data, dict):
        raise ConfigError(f"a config is a mapping of its fields, got {type(data).__name__}")
    data = nest_soccer_keys(dict(data))
    env = data.pop("env", None)
    cfg = from_dict(TrainConfig, data)
    env_cls = type(default_config(cfg.task))
    return dataclasses.replace(cfg, env=from_dict(env_cls, env, "env.") if env is not None else None).resolved()
