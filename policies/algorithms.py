"""The rsl-rl algorithm of each training method (`TrainConfig.algo`): which observation groups its networks
read, which model classes it builds, and which loss it adds.

| algo       | actor (deployed inputs)                     | critic / teacher             | loss                  |
|------------|---------------------------------------------|------------------------------|-----------------------|
| ppo        | MLP on state (+ CNN on camera)              | MLP on privileged_state      | PPO                   |
| teacher    | head on (state, z_p = enc(privileged_state)) | MLP on privileged_state      | PPO                   |
| hib        | head on (state, z ~ q(z | history))         | MLP on privileged_state      | PPO + HIB (policies.hib) |
| hib-no-ib  | as hib                                      | MLP on privileged_state      | PPO                   |
| history    | head on (state, enc(history))               | head on (state, enc(history)) | PPO                  |
| dagger     | head on (state, enc(history))               | the teacher's actor          | behaviour cloning     |
| rma        | teacher's head on (state, enc(history))     | the teacher's actor          | z regression (policies.students) |
| kl         | CNN + MLP on (state, camera)                | MLP on privileged_state      | PPO + KL to a state teacher (policies.teacher_kl) |

A dagger or kl vision student with `distill.student_memory` has a GRU between its features and its head
(policies.memory_models).

Vision students (dagger and kl on soccer-1v1-vision) read (state, camera), and their teacher, a state soccer
player, reads `features`.

enc(history) is `latent.history_encoder` (HistoryConv by default) for every method that reads the history.
"""

from __future__ import annotations

import contextlib
import io
import math

import torch
from rsl_rl.algorithms import PPO
from rsl_rl.models import MLPModel
from rsl_rl.utils import resolve_class
from tensordict import TensorDict

from legged.envs.api import layout_slices
from legged.soccer.vision.estimates import label_groups
from legged.soccer.walker import COMMAND_SIZE
from policies.config import HISTORY_ALGOS, PPOConfig, TrainConfig
from policies.distributed import Launch
from policies.hib import InformationBottleneck
from policies.latent_models import NOISE_GROUP, LatentActor
from policies.memory_models import MemoryCNNModel
from policies.students import LatentRegression, MixedDAgger
from policies.teacher_kl import TeacherKL

CAMERA_CNN = {"output_channels": [16, 32, 32], "kernel_size": [5, 3, 3], "stride": [2, 2, 2], "padding": "zeros",
              "activation": "elu", "global_pool": "none", "flatten": True}
"""The actor's image encoder when the task has a `camera` observation (40 x 30 -> 20 x 15 -> 10 x 7 -> 5 x 3, 32
channels, flattened to 480: no global pooling, which would lose where in the image the ball and goals are)."""

DYNAMICS_GROUPS = ("dynamics", "com", "motor_strength", "model_dynamics", "friction_cone")
"""Entries of `privileged_state` that hold an episode's randomised parameters (probe targets, HIB negatives)."""


def actor_inputs(algo: str, camera: bool = False) -> list[str]:
    """Observation groups the deployed actor of `algo` reads, in its input order (camera tasks: the state and
    the image, for ppo and the vision students alike)."""
    if camera:
        return ["state", "camera"]
    if algo == "teacher":
        return ["state", "privileged_state"]
    if algo in HISTORY_ALGOS:
        return ["state", "history"]
    return ["state"]


def teacher_inputs(teacher: TrainConfig) -> list[str]:
    """Observation groups a distillation's teacher reads in its student's environment: a privileged teacher's
    own; a state soccer player's state features, which its vision task gives as `features`."""
    return ["features"] if teacher.algo == "ppo" else actor_inputs(teacher.algo)


def _mlp(hidden, activation: str, normalize: bool, std: float | None = None, camera: bool = False) -> dict:
    cfg = {"class_name": "MLPModel", "hidden_dims": list(hidden), "activation": activation,
           "obs_normalization": normalize}
    if std is not None:
        cfg["distribution_cfg"] = {"class_name": "GaussianDistribution", "init_std": std}
        if camera:
            cfg.update(class_name="CNNModel", cnn_cfg=dict(CAMERA_CNN))
    return cfg


def actor_model(config: TrainConfig, std: float, camera: bool = False) -> dict:
    """rsl-rl model config of the actor of `config.algo` (dagger: of its student)."""
    ppo, lat, algo = config.ppo, config.latent, config.algo
    base = _mlp(ppo.actor_hidden, ppo.activation, ppo.obs_normalization, std, camera)
    if camera and algo in ("dagger", "kl") and config.distill.student_memory:
        base.update(class_name=MemoryCNNModel, memory_dim=config.distill.student_memory)
    if algo in ("teacher",) + HISTORY_ALGOS and not camera:
        base.update(_latent(lat), gaussian=algo in ("hib", "hib-no-ib"),
                    privileged_embedding=lat.projection_dim if algo in ("hib", "hib-no-ib") else 0)
    return base


def _latent(lat) -> dict:
    """Model settings of a LatentActor (an encoder of the second group, a head on (state, z))."""
    return dict(class_name=LatentActor, latent_dim=lat.latent_dim, encoder_hidden=list(lat.encoder_hidden),
                history_encoder=lat.history_encoder)


def critic_model(config: TrainConfig) -> dict:
    """rsl-rl model config of the critic: an MLP on privileged_state; for `history` (no privileged
    information) a head on (state, encoder(history)) like its actor."""
    ppo = config.ppo
    base = _mlp(ppo.critic_hidden, ppo.activation, ppo.obs_normalization)
    if config.algo == "history":
        base.update(_latent(config.latent))
    return base


def ppo_train_cfg(config: TrainConfig, camera: bool = False, multi_gpu: dict | None = None) -> dict:
    """rsl-rl's train_cfg of a PPO-trained algorithm (ppo, teacher, hib, hib-no-ib, history)."""
    ppo, algo = config.ppo, config.algo
    actor = actor_inputs(algo, camera) + ([NOISE_GROUP] if algo in ("hib", "hib-no-ib") else [])
    critic = ["state", "history"] if algo == "history" else ["privileged_state"]
    return {
        "algorithm": {"class_name": "PPO", "learning_rate": ppo.learning_rate, "num_learning_epochs":
                      ppo.num_learning_epochs, "num_mini_batches": ppo.num_mini_batches, "clip_param":
                      ppo.clip_param, "gamma": ppo.gamma, "lam": ppo.lam, "entropy_coef": ppo.entropy_coef,
                      "value_loss_coef": ppo.value_loss_coef, "desired_kl": ppo.desired_kl,
                      "max_grad_norm": ppo.max_grad_norm, "schedule": ppo.schedule,
                      "use_mixed_precision": ppo.mixed_precision},
        "actor": actor_model(config, ppo.init_noise_std, camera),
        "critic": critic_model(config),
        "obs_groups": {"actor": actor, "critic": critic},
        "num_steps_per_env": ppo.num_steps_per_env,
        "multi_gpu": multi_gpu,
    }


class PriorCorrector(MLPModel):
    """The actor of a state soccer player whose commands corrected the placo player's (command_prior=placo), as
    its vision student's teacher: its outputs, and its Gaussian's mean, are the whole command, its corrections
    added to the observation `command_prior` (the student's game gives it; legged.soccer.learner). The mean is
    clipped to the walker's command range [-1, 1], as the walker clips commands (`Walker.command`): beyond it
    every command walks the same, so neither DAgger's labels nor the KL to the teacher should weigh the excess."""

    def forward(self, obs: TensorDict, masks=None, hidden_state=None, stochastic_output: bool = False):
        mean = (self.mlp(self.get_latent(obs, masks, hidden_state)) + obs["command_prior"]).clamp(-1.0, 1.0)
        if stochastic_output:
            self.distribution.update(mean)
            return self.distribution.sample()
        return self.distribution.deterministic_output(mean)


class WorldLabeller(MLPModel):
    """The actor of a state soccer player whose commands corrected the placo player's (command_prior=placo), as
    the teacher of a vision student that adds the placo command to its own from its estimate of the game
    (legged.soccer.learner, `estimates_world`): its labels are [its corrections (`corrections`), the game
    features after the proprioception that it read (`features`)], the student's actions. Given the placo command
    at the true state (the observation `command_prior`), the corrections are what a clip of the sum to
    [-1 - margin, 1 + margin] leaves of them (the clipped sum less that command; margin 0: what the walker's
    clip leaves; inf, the default: the raw corrections). The teacher's raw corrections are mostly beyond the
    walker's clip (mean square 3-10 against 0.6-0.9 once clipped), yet their excess helps: a command the teacher
    saturates stays saturated when the student's own placo command, from its estimate, is off (docs/vision-students.md,
    the table of students: raw labels scored best, margin 1 next, margin 0 worst)."""

    def __init__(self, obs: TensorDict, obs_groups: dict, obs_set: str, output_dim: int, corrections: int = 3,
                 margin: float = math.inf, **kwargs):
        super().__init__(obs, obs_groups, obs_set, corrections, **kwargs)
        self.world_size, self.margin = output_dim - corrections, margin

    def forward(self, obs: TensorDict, masks=None, hidden_state=None, stochastic_output: bool = False):
        corrections = super().forward(obs, masks, hidden_state, stochastic_output)
        if "command_prior" in obs.keys() and math.isfinite(self.margin):
            prior, bound = obs["command_prior"], 1.0 + self.margin
            corrections = (corrections + prior).clamp(-bound, bound) - prior
        return torch.cat([corrections, obs["features"][..., -self.world_size:]], dim=-1)


def teacher_model(teacher: TrainConfig, student: TrainConfig | None = None) -> dict:
    """rsl-rl model config of a distillation's teacher: the `teacher` run's actor (for a state player with
    soccer.command_prior: a PriorCorrector, or a WorldLabeller when its `student` estimates the world)."""
    cfg = actor_model(teacher, teacher.ppo.init_noise_std)
    if teacher.soccer.command_prior and student is not None and student.estimates_world:
        cfg.update(class_name=WorldLabeller, corrections=COMMAND_SIZE, margin=student.distill.correction_margin)
    elif teacher.soccer.command_prior:
        cfg["class_name"] = PriorCorrector
    return cfg


def weighted_labels(config: TrainConfig) -> dict:
    """MixedDAgger's `label_groups` (name -> [start, stop)) and `label_weights` (one per action) for a student
    that estimates the game (none for others): `distill.label_weights`, else 1, and 0 for the opponents in the
    empty-goal drill (there are none to estimate; the parked robot would teach it a wrong place)."""
    if not config.estimates_world:
        return {}
    groups, weights = label_groups(config.env.scene.players_per_team), []
    for name, part in groups.items():
        opponent = name.rstrip("0123456789") == "opponent"  # opponent0, ...; not opponent_goal
        default = 0.0 if config.soccer.drill == "empty-goal" and opponent else 1.0
        weights += [config.distill.label_weights.get(name, default)] * (part.stop - part.start)
    return {"label_groups": {name: (part.start, part.stop) for name, part in groups.items()},
            "label_weights": weights}


def distill_train_cfg(config: TrainConfig, teacher: TrainConfig, multi_gpu: dict | None = None,
                      camera: bool = False) -> dict:
    """rsl-rl's train_cfg of a distillation (dagger, rma) from the `teacher` run's config."""
    d = config.distill
    student = actor_model(config, d.student_noise_std, camera)
    if config.algo == "rma":  # the teacher's head and latent size, a history encoder of the student's own
        student.update(hidden_dims=list(teacher.ppo.actor_hidden), activation=teacher.ppo.activation,
                       latent_dim=teacher.latent.latent_dim)
    return {
        "algorithm": {"class_name": LatentRegression if config.algo == "rma" else MixedDAgger,
                      "learning_rate": d.learning_rate, "num_learning_epochs": d.num_learning_epochs,
                      "gradient_length": d.gradient_length, "max_grad_norm": config.ppo.max_grad_norm,
                      **({} if config.algo == "rma" else {"teacher_act_fraction": d.teacher_act_fraction,
                                                          "teacher_act_iterations": d.teacher_act_iterations,
                                                          **weighted_labels(config)})},
        "student": student,
        "teacher": teacher_model(teacher, config),
        "obs_groups": {"student": actor_inputs(config.algo, camera), "teacher": teacher_inputs(teacher)},
        "num_steps_per_env": config.ppo.num_steps_per_env,
        "multi_gpu": multi_gpu,
    }


def dummy_observations(obs_sizes: dict, num_envs: int = 1) -> TensorDict:
    """Zero observations of the given sizes (to build networks without an environment)."""
    shape = lambda n: (n,) if isinstance(n, int) else tuple(n)
    return TensorDict({k: torch.zeros(num_envs, *shape(n)) for k, n in obs_sizes.items()}, batch_size=[num_envs])


class _Shapes:
    """The little of a VecEnv that building an algorithm needs."""

    def __init__(self, num_envs: int, num_actions: int):
        self.num_envs, self.num_actions = num_envs, num_actions


def build_ppo(obs: TensorDict, num_envs: int, num_actions: int, ppo: PPOConfig, device: str,
              launch: Launch = Launch()) -> PPO:
    """rsl-rl PPO of the plain `ppo` algorithm (actor on `state`)."""
    return build_algorithm(TrainConfig(task="go1-flat", ppo=ppo), obs, num_envs, num_actions, device, launch)


def build_algorithm(config: TrainConfig, obs: TensorDict, num_envs: int, num_actions: int, device: str,
                    launch: Launch = Launch(), teacher: TrainConfig | None = None):
    """The rsl-rl algorithm of `config.algo` with its networks and rollout storage (gradients averaged over
    `launch`'s processes); distillations need the `teacher` run's config."""
    camera = "camera" in obs.keys()
    with contextlib.redirect_stdout(io.StringIO()):  # rsl-rl prints the whole network
        if config.algo in ("dagger", "rma"):
            if teacher is None:
                raise ValueError(f"--algo {config.algo} needs the teacher run's config")
            cfg = distill_train_cfg(config, teacher, launch.multi_gpu_config(), camera)
            return cfg["algorithm"]["class_name"].construct_algorithm(obs, _Shapes(num_envs, num_actions), cfg, device)
        alg = PPO.construct_algorithm(obs, _Shapes(num_envs, num_actions),
                                      ppo_train_cfg(config, camera, launch.multi_gpu_config()), device)
    if config.ppo.zero_action_init:
        zero_output_layer(alg.actor)
    return alg


def zero_output_layer(actor: torch.nn.Module) -> None:
    """Set the last linear layer of `actor`'s MLP to zero: its mean action starts at 0 (a residual policy then
    plays its reference) and learns from there (that layer's gradient is not zero)."""
    last = [m for m in actor.mlp.modules() if isinstance(m, torch.nn.Linear)][-1]
    with torch.no_grad():
        last.weight.zero_()
        last.bias.zero_()


def privileged_slices(layout: dict, names=DYNAMICS_GROUPS) -> list[slice]:
    """Slices of `privileged_state` holding the named entries (an env's `observation_layout()`)."""
    return [part for name, part in layout_slices(layout["privileged_state"]).items() if name in names]


def attach_teacher_kl(alg: PPO, config: TrainConfig, teacher: TrainConfig, payload: dict, obs: TensorDict,
                      num_actions: int, iteration: int) -> None:
    """Give a kl student's PPO its pull towards the frozen teacher (policies.teacher_kl), the teacher's actor
    rebuilt from its config and loaded from its checkpoint `payload`, with as many outputs as the student's
    `num_actions` (policies.students.load_teacher checked them: the teacher's, and for a student that estimates
    the game, a WorldLabeller's, the game features after them)."""
    cls, kwargs = resolve_class(teacher_model(teacher, config))
    model = cls(obs, {"teacher": teacher_inputs(teacher)}, "teacher", num_actions, **kwargs)
    model.load_state_dict(payload["alg"]["actor_state_dict"], strict=True)
    d = config.distill
    alg.symmetry = TeacherKL(model, d.kl_weight, d.kl_decay, iteration, actor=alg.actor,
                             critic_warmup=d.critic_warmup)


def attach_information_bottleneck(alg: PPO, config: TrainConfig, layout: dict, seed: int) -> None:
    """Give a hib / hib-no-ib PPO its information-bottleneck loss (policies.hib)."""
    lat = config.latent
    alg.symmetry = InformationBottleneck(lat.kl_weight, lat.infonce_weight, lat.temperature, lat.infonce_samples,
                                         privileged_slices(layout), ib=config.algo == "hib", seed=seed)
