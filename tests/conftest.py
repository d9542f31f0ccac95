"""Shared fixtures: environments are compiled once per test session (compilation dominates CPU time)."""

import os

import jax
import pytest

import legged  # noqa: F401  (quiet MJX import)
from legged.tasks import make
from legged.envs.config import NoiseConfig, RandomizationConfig
from legged.envs.confined import ConfinedConfig, ConfinedEnv
from legged.envs.physics import view_of_mjx
from legged.worlds import Terrain, generate_world

XLA_OPTIMIZE = os.environ.get("LEGGED_TEST_XLA_OPTIMIZE") == "1"
"""XLA compiles without its costly optimisation passes in the suite, here and (through the environment variable) in
the processes tests start: compiling, not running, is most of the suite's time (736 -> 566 s of pytest wall time on
2 cores, 2026-12-06). The programs run the same operations, slower, and may round differently in the last bits;
`LEGGED_TEST_XLA_OPTIMIZE=1` keeps the passes, e.g. to chase a difference between the suite and a real run."""
jax.config.update("jax_disable_most_optimizations", not XLA_OPTIMIZE)
if not XLA_OPTIMIZE:
    os.environ["JAX_DISABLE_MOST_OPTIMIZATIONS"] = "1"

BATCH = 8
"""Every test uses this one batch size: each new size would compile the env again (about a minute)."""
TINY_EPISODE_S = 0.2
"""Episodes of the tiny training runs: 10 control steps, so that episodes end inside a tiny run."""
TINY_RUN = ["env.episode_seconds=0.2", "ppo.num_steps_per_env=5", "ppo.num_mini_batches=2", "checkpoint_every=1",
            "ppo.actor_hidden=[32, 32]", "ppo.critic_hidden=[32, 32]", "random_episode_start=false",
            "randomization_curriculum=0"]
"""Overrides of the tiny go1-flat runs: 8 envs x 5 steps = 40 env steps per iteration; episodes end in
iteration 2 (the go1-flat recipe's random episode start and randomisation curriculum off: tests/test_recipes.py)."""


HEAVIEST_FILES = ("test_envs.py", "test_vision_distill.py", "test_dashboard.py", "test_walker.py", "test_soccer_env.py",
                  "test_distributed.py", "test_skills.py", "test_mjx_randomized.py", "test_op3_randomize.py",
                  "test_training.py", "test_native_raycam.py", "test_soccer_training.py", "test_steered.py",
                  "test_native.py", "test_follower.py", "test_training_brax.py", "test_distill.py")
"""Test files by their measured time, longest first (`--durations=0` on a 2-core machine, 2026-12-06: the group of
test_envs.py ~180 s, test_vision_distill ~125, test_dashboard ~80, ... down to ~20 s). They start first so that
pytest-xdist's two workers end together: a long file handed out last keeps one worker busy after the other has
finished. The other files follow in their usual order."""


SHARED_COMPILATIONS = {name: "go1-mjx" for name in ("test_envs.py", "test_mjx_vs_native.py", "test_native.py",
                                                      "test_heightscan.py", "test_follower.py")}
"""Files that use the session's `flat` and `confined` envs run in one process: a fixture is built and compiled once
per process, and building the confined env and tracing the two envs again in another process took minutes on a
slow machine (the persistent XLA cache below saves their compilation, not their tracing)."""


SLOW_FILES = ("test_vision_distill.py", "test_soccer_env.py", "test_envs.py", "test_dashboard.py", "test_training.py",
              "test_distributed.py", "test_walker.py", "test_skills.py", "test_mjx_vs_native.py",
              "test_mjx_randomized.py", "test_op3_randomize.py", "test_native_raycam.py", "test_soccer_training.py",
              "test_steered.py", "test_op3_fidelity.py", "test_training_brax.py", "test_follower.py", "test_native.py",
              "test_distill.py", "test_placo_player.py", "test_resume_losses.py", "test_raycam.py", "test_tracker.py",
              "test_randomize.py", "test_peer_dm_control.py")
"""Files whose tests compile environments, train, or drive a browser (each over 14 s of test time on 2 cores,
`--durations=0`, 2026-12-04): every test in them is marked `slow`. `pytest -m "not slow"` is the fast tier for
development (every module still imported by tests/test_layers.py); the full suite runs everything."""


def _group(path: str) -> str:
    """The scheduling unit of a test file: its SHARED_COMPILATIONS group, or the file itself."""
    return SHARED_COMPILATIONS.get(os.path.basename(path), path)


def pytest_collection_modifyitems(items):
    """Mark the tests of SLOW_FILES `slow`; run the heaviest test files first (HEAVIEST_FILES), the files of a
    SHARED_COMPILATIONS group together (at the place of the group's heaviest file); with `--no-loadscope-reorder`
    pytest-xdist keeps this order."""
    for item in items:
        if item.path.name in SLOW_FILES:
            item.add_marker(pytest.mark.slow)
    rank = {name: k for k, name in enumerate(HEAVIEST_FILES)}
    first = {}
    for item in items:
        group = _group(str(item.path))
        first[group] = min(first.get(group, len(rank)), rank.get(item.path.name, len(rank)))
    items.sort(key=lambda item: first[_group(str(item.path))])  # stable: the rest keep their order


def pytest_xdist_make_scheduler(config, log):
    """`--dist loadfile`, with the files of a SHARED_COMPILATIONS group handed to one process as one unit."""
    from xdist.scheduler import LoadScopeScheduling

    class FileGroupScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return _group(nodeid.split("::", 1)[0])

    return FileGroupScheduling(config, log)


class Compiled:
    """An env with its batched reset, step and transition jitted once."""

    def __init__(self, env):
        self.env = env
        self.reset = jax.jit(jax.vmap(env.reset))
        self.step = jax.jit(jax.vmap(env.step))
        self.transition = jax.jit(jax.vmap(env.transition))
        self.contact_forces = jax.jit(jax.vmap(env.contact_forces))
        self.view = jax.jit(jax.vmap(lambda data: view_of_mjx(data, env.contact_forces(data), False)))
        """The PhysicsView of a batch of MJX data (what `transition` reads)."""

    def keys(self, seed=0):
        return jax.random.split(jax.random.PRNGKey(seed), BATCH)


@pytest.fixture(scope="session")
def flat():
    """go1-flat on the nominal model: no randomisation, no observation noise (the task trains with both)."""
    return Compiled(make("go1-flat", randomization=RandomizationConfig(), noise=NoiseConfig()))


@pytest.fixture(scope="session")
def confined():
    terrain = Terrain.from_worlds([generate_world(11, 0), generate_world(12, 2)])
    return Compiled(ConfinedEnv(ConfinedConfig(mode="waypoints", randomization=RandomizationConfig(),
                                               noise=NoiseConfig()), terrain=terrain))


@pytest.fixture(scope="session", autouse=True)
def compilation_cache(tmp_path_factory):
    """A per-run persistent XLA cache: a program compiled twice in one run of the suite (a training run and
    its resume, or the same environment in two test files) is compiled once, also across pytest-xdist's
    workers, which share the run's temporary root. A fresh directory keeps every run independent of
    earlier ones."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        cache = tmp_path_factory.getbasetemp().parent / "xla-cache"
        cache.mkdir(exist_ok=True)
    else:
        cache = tmp_path_factory.mktemp("xla-cache")
    jax.config.update("jax_compilation_cache_dir", str(cache))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.5)
    yield
    jax.config.update("jax_compilation_cache_dir", None)
