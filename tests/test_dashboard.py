"""The dashboard (web/): geoms -> meshes -> scene nodes, recorded trajectories, early errors, and a real
browser session (headless Chromium with software WebGL) that renders the scene and plays the timeline."""

import io
import os
import shutil
import socket
import subprocess
import sys
import threading
import time
from contextlib import redirect_stderr
from pathlib import Path

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest

import legged  # noqa: F401  (quiet MJX import)
from legged.cli import main
from legged.tasks import make
from legged.envs.confined import ConfinedConfig, ConfinedEnv
from legged.robots import GO1
from legged.worlds import Terrain, generate_world
from web.geometry import box_mesh, capsule_mesh, cylinder_mesh, geom_meshes, sphere_mesh
from web.overlays import OVERLAYS
from web.trajectory import load_trajectory

ROOT = Path(__file__).resolve().parents[1]
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
STEPS = 50
"""Control steps recorded for the tests (1 s of simulated time)."""
WAIT_S = 600.0
"""Longest wait for the dashboard (its start, a page element, a drawing): a guard against hangs, not a speed check.
Every wait ends as soon as its condition holds; on a machine several times slower than usual the soccer
dashboard's start alone took over 3 minutes."""
VISION_STUDENT = ROOT / "assets/policies/op3-soccer-1v1-vision"
"""A trained vision student that estimates the ball, goals and opponent from its camera and its camera's sightings of
the ball and goals, and steers by its tracker (the run behind the shipped camera player)."""
PILOTED_STUDENT = ROOT / "assets/policies/op3-soccer-1v1-vision-piloted"
"""The same network, shipped steered from its estimate by a state pilot (its config's `soccer.pilot`)."""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def confined_env():
    """A one-world waypoint task with a planned path (built like the demo: no plan cache involved)."""
    from planners import HeightMaps, PlannerConfig, plan_path

    world = generate_world(0, 0)
    plan = plan_path(HeightMaps.from_world(world), world.start, world.goal, GO1, PlannerConfig())
    return ConfinedEnv(ConfinedConfig(mode="waypoints", num_worlds=1), terrain=Terrain.from_worlds([world]),
                       paths=[plan.waypoints])


@pytest.fixture(scope="module")
def recorded(confined_env, tmp_path_factory):
    """A rollout of the default controller and its saved file. In native physics: the recorder's MJX branch
    would compile one more confined-world program (about 5 minutes on a slow 2-core machine) for what
    tests/test_mjx_vs_native.py already holds to native MuJoCo."""
    from web.rollout import Recorder, RecorderConfig

    traj = Recorder(confined_env, "confined-waypoints", RecorderConfig(physics="native")).record(STEPS, seed=0)
    return traj, traj.save(tmp_path_factory.mktemp("trajectory") / "rollout.npz")


@pytest.fixture(scope="module")
def server():
    import viser

    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


def signed_volume(vertices, faces) -> float:
    a, b, c = (vertices[faces[:, k]].astype(np.float64) for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6)


def test_primitive_meshes_are_closed_and_face_outward():
    assert signed_volume(*box_mesh(np.array([0.1, 0.2, 0.3]))) == pytest.approx(0.048)
    assert signed_volume(*sphere_mesh([0.5, 0.5, 0.5])) == pytest.approx(4 / 3 * np.pi / 8, rel=0.05)
    assert signed_volume(*sphere_mesh([0.1, 0.2, 0.3])) == pytest.approx(4 / 3 * np.pi * 0.006, rel=0.05)
    assert signed_volume(*capsule_mesh(0.1, 0.2)) == pytest.approx(np.pi * 0.01 * 0.4 + 4 / 3 * np.pi * 1e-3, rel=0.05)
    assert signed_volume(*cylinder_mesh(0.1, 0.2)) == pytest.approx(np.pi * 0.01 * 0.4, rel=0.05)


def test_height_field_mesh_matches_the_model(confined_env):
    model = confined_env.mj_model
    meshes = geom_meshes(model)
    for name in ("floor", "ceiling"):
        mesh = meshes[model.geom(name).id]
        h = model.geom_dataid[mesh.geom]
        nrow, ncol = model.hfield_nrow[h], model.hfield_ncol[h]
        sx, sy, sz, _ = model.hfield_size[h]
        top = mesh.vertices[: nrow * ncol].reshape(nrow, ncol, 3)
        heights = model.hfield_data[model.hfield_adr[h]: model.hfield_adr[h] + nrow * ncol].reshape(nrow, ncol)
        np.testing.assert_allclose(top[..., 2], sz * heights, atol=1e-5)
        np.testing.assert_allclose(top[0, 0, :2], [-sx, -sy], atol=1e-5)
        np.testing.assert_allclose(top[-1, -1, :2], [sx, sy], atol=1e-5)
        assert signed_volume(mesh.vertices, mesh.faces) > 0  # closed by side walls and a bottom, facing out
    # Placed at the geom's pose, surface vertices lie where MuJoCo's own ray casts meet the height fields.
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    terrain_only = np.array([1, 0, 0, 0, 0, 0], np.uint8)
    for name, direction in (("floor", -1.0), ("ceiling", 1.0)):
        geom = model.geom(name).id
        mesh = meshes[geom]
        h = model.geom_dataid[geom]
        picks = np.random.default_rng(0).integers(0, model.hfield_nrow[h] * model.hfield_ncol[h], 20)
        world = data.geom_xpos[geom] + mesh.vertices[picks].astype(np.float64) @ data.geom_xmat[geom].reshape(3, 3).T
        for point in world:
            start = point - np.array([0.0, 0.0, 0.01 * direction])
            hit = mujoco.mj_ray(model, data, start, np.array([0.0, 0.0, direction]), terrain_only, 1, -1,
                                np.zeros(1, np.int32))
            assert hit == pytest.approx(0.01, abs=2e-4), (name, point)


@pytest.mark.parametrize("scene", ["confined", "go1-flat", "soccer-2v2"])
@pytest.mark.parametrize("num_envs", [1, 2])
def test_every_geom_becomes_a_scene_node(scene, num_envs, confined_env, server):
    from web.scene import SceneView, static_bodies

    model = confined_env.mj_model if scene == "confined" else make(scene).mj_model
    server.scene.reset()
    view = SceneView(server.scene, model, np.zeros((num_envs, 3)))
    static = static_bodies(model)[model.geom_bodyid]
    assert len(view.geom_nodes) == static.sum() + num_envs * (~static).sum()
    if num_envs == 1:
        assert len(view.geom_nodes) == model.ngeom
        assert sorted(g for _, g, _ in view.geom_nodes) == list(range(model.ngeom))
    for mesh in view.meshes:
        assert len(mesh.faces) and mesh.faces.max() < len(mesh.vertices) and np.isfinite(mesh.vertices).all()
    ceiling = view.ceiling_nodes()
    if scene == "confined":
        assert len(ceiling) == 1 and ceiling[0].opacity is not None and ceiling[0].opacity <= 0.35
        view.set_ceiling(False, 0.2)
        assert not ceiling[0].visible
    elif scene == "go1-flat":
        assert ceiling == []
        floor = view.meshes[model.geom("floor").id]
        assert floor.kind == "plane" and np.ptp(floor.vertices[:, 0]) == pytest.approx(20.0)  # infinite -> 20 m


def test_recorded_trajectory_round_trips(recorded):
    traj, path = recorded
    loaded = load_trajectory(path)
    assert loaded.num_frames == STEPS + 1 and loaded.num_envs == 1
    assert loaded.model.ngeom == traj.model.ngeom and loaded.model.nq == traj.model.nq
    for name in ("qpos", "reward", "done", "offsets", "paths", "path_len", "waypoint", "goal", "floor_scan",
                 "ceiling_scan"):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(traj, name), err_msg=name)
    assert loaded.metrics.keys() == traj.metrics.keys() and loaded.info == traj.info
    assert loaded.info["policy"] == "default controller"
    # Go1 stands under the default controller; scans lie on the floor and ceiling around it.
    assert 0.2 < loaded.qpos[-1, 0, 2] < 0.35
    assert np.all(loaded.ceiling_scan[..., 2] > loaded.floor_scan[..., 2])
    assert np.linalg.norm(loaded.floor_scan[0, 0, :, :2].mean(0) - loaded.qpos[0, 0, :2]) < 1.0
    assert loaded.path_len[0] >= 2 and np.allclose(loaded.paths[0, 0, :2], loaded.qpos[0, 0, :2], atol=0.05)


def test_trajectory_file_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="not found"):
        load_trajectory(tmp_path / "missing.npz")
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(ValueError, match="not a legged trajectory"):
        load_trajectory(tmp_path / "other.npz")


def test_training_curves_and_checkpoints_follow_a_running_training(tmp_path, server):
    from policies.run_dir import RunDir
    from web.panels import CheckpointPicker, TrainingCurves

    metrics = tmp_path / "metrics.jsonl"
    metrics.write_text('{"step": 10, "episode_return": null}\n{"step": 20, "episode_return": 1.5}\n{"step": 3')
    assert [r["step"] for r in RunDir(tmp_path).metrics()] == [10, 20]  # the line being written is skipped
    curves = TrainingCurves(server.gui, RunDir(tmp_path))
    assert curves.refresh() is False  # unchanged file
    with open(metrics, "a") as f:
        f.write('0, "episode_return": 2.5, "loss": 0.1}\n')
    assert curves.refresh() is True
    assert "3 records, last at step 30" in curves.status.content
    assert set(curves.key.options) >= {"episode_return", "loss"}
    np.testing.assert_array_equal(curves._plot.handle.data[1], [1.5, 2.5])  # null returns are left out
    assert curves.diagnostics.folder is None  # no latent: no diagnostics folder
    with open(metrics, "a") as f:
        f.write('{"step": 40, "hib_kl": 3.0, "hib_mi_lower_bound": 1.2, "probe_r2": null}\n'
                '{"step": 50, "hib_kl": 2.0, "hib_mi_lower_bound": 1.9, "probe_r2": 0.4}\n')
    assert curves.refresh() is True
    assert set(curves.diagnostics.plots) == {"hib_kl", "hib_mi_lower_bound", "probe_r2"}
    np.testing.assert_array_equal(curves.diagnostics.plots["hib_kl"].handle.data[1], [3.0, 2.0])
    np.testing.assert_array_equal(curves.diagnostics.plots["probe_r2"].handle.data, [[50.0], [0.4]])

    checkpoints = [tmp_path / "step_000000000010.pt"]
    loaded = []
    picker = CheckpointPicker(server.gui, lambda: list(checkpoints), loaded.append)
    assert picker.dropdown.value == "step_000000000010.pt"
    checkpoints.append(tmp_path / "step_000000000020.pt")
    assert picker.refresh() and picker.dropdown.value == "step_000000000020.pt"  # follows the newest
    picker._load()
    assert loaded == [checkpoints[1]]


def _view_error(*args) -> str:
    err = io.StringIO()
    with redirect_stderr(err):
        assert main(["view", *args]) == 2
    return err.getvalue()


def test_view_errors_name_the_cause_before_long_work(tmp_path):
    port = free_port()
    assert "run directory not found" in _view_error(str(tmp_path / "nope"), "--port", str(port))
    assert "unknown task 'nope'" in _view_error("--task", "nope", "--port", str(port))
    assert "unknown drill 'nope'" in _view_error("--drill", "nope", "--port", str(port))
    assert "the walk drill needs placo or an op3-walk run" in _view_error(str(VISION_STUDENT), "--drill", "walk",
                                                                          "--port", str(port))
    run = tmp_path / "run"
    (run / "checkpoints").mkdir(parents=True)
    shutil.copy(ROOT / "assets/runs/go1-flat-rsl-cpu2/config.yaml", run / "config.yaml")
    (run / "checkpoints" / "step_000000001000.pt").write_text("not a checkpoint")
    assert "cannot be read" in _view_error(str(run), "--port", str(port))
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        taken = busy.getsockname()[1]
        assert f"port {taken} on 127.0.0.1 is in use" in _view_error("--port", str(taken))


class Output:
    """Reads a process's output on a thread (so its pipe never fills) and waits for a line."""

    def __init__(self, proc: subprocess.Popen):
        self.lines: list[str] = []
        self._thread = threading.Thread(target=lambda: self.lines.extend(iter(proc.stdout.readline, "")),
                                        daemon=True)
        self._thread.start()
        self.proc = proc

    def wait_for(self, text: str, timeout: float) -> str:
        def found():
            hits = [line for line in self.lines if text in line]
            if not hits and self.proc.poll() is not None:
                raise AssertionError(f"the process exited ({self.proc.returncode}):\n{''.join(self.lines)}")
            return hits[0] if hits else None

        return _poll(found, timeout, repr(text))


def _canvas_stats(png: bytes) -> tuple[float, int]:
    import imageio.v3 as iio

    pixels = iio.imread(png)[..., :3].reshape(-1, 3)
    return float(pixels.std(axis=0).mean()), len(np.unique(pixels // 16, axis=0))


def _poll(check, timeout: float, what: str):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        result = check()
        if result:
            return result
        time.sleep(0.5)
    raise AssertionError(f"timed out after {timeout:.0f} s waiting for {what}")


@pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not installed (CI installs it: .ci/install)")
def test_dashboard_in_headless_chromium(recorded, tmp_path):
    playwright = pytest.importorskip("playwright.sync_api", reason="playwright is a dev dependency")
    _, path = recorded
    run = tmp_path / "run"  # a run whose metrics hold a latent's diagnostics (HIB's bounds, the probe)
    run.mkdir()
    shutil.copy(ROOT / "assets/runs/go1-flat-rsl-cpu2/config.yaml", run / "config.yaml")
    (run / "metrics.jsonl").write_text("".join(
        f'{{"step": {k * 100}, "episode_return": {k}, "hib_kl": {3.0 - k}, "hib_mi_lower_bound": {0.5 * k}, '
        f'"probe_r2": {0.1 * k}}}\n' for k in range(1, 4)))
    port = free_port()
    command = [sys.executable, "-m", "legged.cli", "view", str(run), "--trajectory", str(path), "--port", str(port)]
    proc = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        line = Output(proc).wait_for("[view] dashboard at", WAIT_S)
        assert f"http://127.0.0.1:{port}" in line
        with playwright.sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=[
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"])
            page = browser.new_page(viewport={"width": 1024, "height": 700})
            page.goto(f"http://127.0.0.1:{port}")
            canvas = page.locator("canvas[data-engine]")
            canvas.wait_for(timeout=WAIT_S * 1000)
            page.get_by_text("default controller").first.wait_for(timeout=WAIT_S * 1000)  # the trajectory is shown

            def drawn():
                shot = canvas.screenshot(path=str(tmp_path / "dashboard.png"))
                spread, colours = _canvas_stats(shot)
                return (spread, colours) if spread > 20 and colours >= 8 else None

            spread, colours = _poll(drawn, WAIT_S, "the 3D scene to be drawn")
            assert spread > 20 and colours >= 8  # not a blank or uniform canvas
            page.get_by_role("tab", name="Training").click()  # the run's curves and its latent's plots
            page.get_by_text("3 records, last at step 300").first.wait_for(timeout=WAIT_S * 1000)
            page.get_by_text("Latent diagnostics").first.wait_for(timeout=WAIT_S * 1000)
            page.get_by_role("tab", name="Rollout").click()

            label = page.locator("label", has_text="Timeline")
            slider = page.locator(f"[id='{label.get_attribute('for')}'] [role=slider]")
            start = int(slider.get_attribute("aria-valuenow"))
            assert start == 0 and int(slider.get_attribute("aria-valuemax")) == STEPS
            page.get_by_role("button", name="Play").click()
            _poll(lambda: int(slider.get_attribute("aria-valuenow")) > start, WAIT_S, "the timeline to advance")
            page.get_by_role("button", name="Pause").click()
            browser.close()
    finally:
        proc.terminate()
        proc.wait(timeout=30)


@pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not installed (CI installs it: .ci/install)")
def test_a_soccer_players_head_camera_in_headless_chromium(tmp_path):
    """A vision student's rollout (a trained one that estimates the game, has a tracker and is steered by a state
    pilot) in a game names its pilot, shows its head camera in the Camera tab, and its estimate of the ball, goals
    and opponent, what its camera sights and where its tracker puts it as overlays. (The recording of the same is
    checked without a browser below; one browser session costs minutes.)"""
    playwright = pytest.importorskip("playwright.sync_api", reason="playwright is a dev dependency")
    port = free_port()
    command = [sys.executable, "-m", "legged.cli", "view", str(PILOTED_STUDENT), "--physics", "native",
               "--steps", "10", "--port", str(port)]
    proc = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        Output(proc).wait_for("[view] dashboard at", WAIT_S)
        with playwright.sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=[
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"])
            page = browser.new_page(viewport={"width": 1024, "height": 700})
            page.goto(f"http://127.0.0.1:{port}")
            page.locator("canvas[data-engine]").wait_for(timeout=WAIT_S * 1000)
            page.get_by_text("steered from its estimate by assets/policies/op3-soccer-1v1-pilot-steered").first.wait_for(
                timeout=WAIT_S * 1000)
            page.get_by_role("tab", name="Camera").click()
            page.get_by_text("camera observation recorded by the task").first.wait_for(timeout=WAIT_S * 1000)
            image = page.locator("img").last

            def shown():  # grass, lines and the other robot, not the all-black image shown before one arrives
                spread, colours = _canvas_stats(image.screenshot(path=str(tmp_path / "head_camera.png")))
                return (spread, colours) if spread > 10 and colours >= 3 else None

            _poll(shown, WAIT_S, "the head camera image")
            page.get_by_role("tab", name="Overlays").click()
            for overlay in ("estimate", "sightings", "tracked"):
                label = page.locator("label", has_text=OVERLAYS[overlay])
                label.wait_for(timeout=WAIT_S * 1000)
                box = page.locator(f"[id='{label.get_attribute('for')}']").locator("xpath=descendant-or-self::input")
                _poll(lambda: box.first.is_enabled() or None, WAIT_S, f"the {overlay} overlay to be available")
            browser.close()
    finally:
        proc.terminate()
        proc.wait(timeout=30)


def test_first_view_of_a_confined_world_is_inside_the_tunnel(recorded, confined_env):
    """A newcomer's first view shows the robot from inside its tunnel, under the ceiling, not the roof."""
    from web.app import Dashboard, DashboardConfig

    traj, _ = recorded
    dashboard = Dashboard(DashboardConfig(host="127.0.0.1", port=free_port()), trajectory=traj)
    dashboard.start()
    try:
        eye = np.asarray(dashboard.server.initial_camera.position, float)
        target = np.asarray(dashboard.server.initial_camera.look_at, float)
        assert np.linalg.norm(target[:2] - traj.qpos[0, 0, :2]) < 0.05
        floor, ceiling = (float(f(jnp.asarray(eye[:2]))) for f in (confined_env.floor_height, confined_env.ceiling_height))
        assert floor + 0.05 < eye[2] < ceiling - 0.05
    finally:
        dashboard.stop()


def test_navigation_replans_round_trip_and_show_from_their_frame(recorded, server, tmp_path):
    """A navigation's replanned paths are saved with the trajectory; the dashboard shows each from the frame
    it was made on, and the target marker follows the newest one."""
    import dataclasses

    from web.overlays import Overlays
    from web.trajectory import load_trajectory

    traj, _ = recorded
    replan = traj.paths[:1].copy()
    replan[0, :, 1] += 0.3  # a path shifted sideways, followed from frame 20 on
    nav = dataclasses.replace(traj, replans=replan, replan_len=traj.path_len[:1].copy(), replan_frame=np.array([20]))
    loaded = load_trajectory(nav.save(tmp_path / "nav.npz"))
    np.testing.assert_array_equal(loaded.replans, replan)
    assert loaded.replan_frame.tolist() == [20]
    with pytest.raises(ValueError, match="replan"):
        dataclasses.replace(traj, replans=replan)  # without its lengths and frames
    overlays = Overlays(server.scene, loaded)
    assert overlays.available["replans"]
    overlays.update(10, np.zeros((0, 3)))
    assert not any(node.visible for node in overlays.nodes["replans"])
    target_before = np.array(overlays.nodes["target"][0].position)
    overlays.update(25, np.zeros((0, 3)))
    assert all(node.visible for node in overlays.nodes["replans"])
    index = min(int(loaded.waypoint[25, 0]), int(loaded.replan_len[0]) - 1)
    np.testing.assert_allclose(overlays.nodes["target"][0].position, replan[0, index, :3], atol=1e-6)
    assert not np.allclose(target_before[1], overlays.nodes["target"][0].position[1])
    overlays.set_visible("replans", False)
    assert not any(node.visible for node in overlays.nodes["replans"])
    overlays.remove()


def test_a_vision_students_estimate_of_the_game_is_recorded_in_the_world_and_shown(server, tmp_path):
    """A player that estimates the game (command_prior=placo on the vision task) has its estimate recorded as
    world points; fed the truth, the points are the ball, the goal centres and the opponent. What its camera sights
    (vision_sightings) is recorded too, and shown only while in view."""
    from legged.soccer.learner import LearnerView
    from legged.soccer.observe import PROPRIO_SIZE
    from legged.soccer.pitch import goal_centres
    from policies.policy_io import load_walker
    from web.overlays import Overlays
    from web.rollout import Recorder, RecorderConfig

    view = LearnerView(make("soccer-1v1-vision", vision_sightings=True),
                       walker=load_walker("assets/policies/op3-walker-v1", prior="placo"))
    truth = lambda obs: np.concatenate([np.zeros((len(obs["features"]), 3)), obs["features"][:, PROPRIO_SIZE:]], -1)
    traj = Recorder(view, "soccer-1v1-vision", RecorderConfig(physics="native")).record(3, seed=1, act=truth)
    assert traj.estimates.shape == (4, 1, 4, 3)
    for part in ("ball", "own_goal", "opponent_goal", "first_other"):  # the episode's RMS errors of the truth: 0
        np.testing.assert_allclose(traj.metrics[f"estimate_{part}_m"][1:], 0.0, atol=1e-4)
    layout = view.game.layout
    for frame in range(3):
        qpos = traj.qpos[frame, 0]
        np.testing.assert_allclose(traj.estimates[frame, 0, 0], qpos[layout.ball_qpos_adr:layout.ball_qpos_adr + 3],
                                   atol=1e-4)
        np.testing.assert_allclose(traj.estimates[frame, 0, 1:3], goal_centres(view.config.scene), atol=1e-4)
        opponent = qpos[layout.root_qpos_adr[1]:layout.root_qpos_adr[1] + 2]
        np.testing.assert_allclose(traj.estimates[frame, 0, 3], [*opponent, 0.0], atol=1e-4)
    loaded = load_trajectory(traj.save(tmp_path / "estimate.npz"))
    np.testing.assert_array_equal(loaded.estimates, traj.estimates)
    overlays = Overlays(server.scene, loaded)
    assert overlays.available["estimate"]
    overlays.update(2, np.zeros((0, 3)))
    np.testing.assert_allclose(overlays.nodes["estimate"][0].points, traj.estimates[2, 0], atol=1e-6)
    assert traj.sightings.shape == (4, 1, 3, 3) and overlays.available["sightings"]
    ball = traj.sightings[:, 0, 0]
    in_view = np.isfinite(ball).all(-1)
    assert in_view.all()  # measured at this seed: the ball in every frame, the goals (the default lens) in none
    balls = traj.qpos[:, 0, layout.ball_qpos_adr:layout.ball_qpos_adr + 3]
    assert np.abs(ball[in_view] - balls[in_view]).max() < 0.06
    np.testing.assert_array_equal(loaded.sightings, traj.sightings)
    overlays.update(1, np.zeros((0, 3)))
    node, seen = overlays.nodes["sightings"][0], traj.sightings[1, 0]
    seen = seen[np.isfinite(seen).all(-1)]
    assert node.visible == bool(len(seen))
    if len(seen):
        np.testing.assert_allclose(node.points, seen, atol=1e-6)
    overlays.set_visible("sightings", False)
    assert not node.visible
    overlays.remove()


def test_a_vision_students_tracked_pose_is_recorded_and_shown(server, tmp_path):
    """A player with a tracker (vision_tracker) has where its tracker puts it recorded: its torso and a point
    ahead along its tracked heading once locked on, NaN before; the overlay shows it only once locked on."""
    import dataclasses

    from legged.envs.vector import VectorEnv
    from legged.soccer.learner import TRACKED_ARROW_M, LearnerView
    from legged.soccer.observe import read_bodies
    from legged.soccer.vision.tracker import tracker_kickoff, tracker_start
    from policies.policy_io import load_walker
    from web.overlays import Overlays
    from web.rollout import Recorder, RecorderConfig

    view = LearnerView(make("soccer-1v1-vision", vision_tracker=True),
                       walker=load_walker("assets/policies/op3-walker-v1", prior="placo"))
    traj = Recorder(view, "soccer-1v1-vision", RecorderConfig(physics="native")).record(2, seed=1)
    assert traj.tracked.shape == (3, 1, 2, 3)
    state = jax.tree.map(lambda x: x[0], VectorEnv.of(view, 1, "native", 1).reset(jax.random.PRNGKey(1)).state)
    height = float(read_bodies(view.game.layout, state.pipeline_state.qpos, state.pipeline_state.qvel).pos[0, 2])
    placed = lambda tracker: np.asarray(view.tracked_points(state.replace(info={**state.info, "tracker": tracker})))
    ahead = [0.5 + TRACKED_ARROW_M * np.cos(0.3), -0.2 + TRACKED_ARROW_M * np.sin(0.3), height]
    np.testing.assert_allclose(placed(tracker_kickoff(jnp.array([0.5, -0.2, 0.3]))), [[0.5, -0.2, height], ahead],
                               atol=1e-5)
    assert np.isnan(placed(tracker_start(jnp.array([0.5, -0.2, 0.3])))).all()  # not locked on yet
    tracked = np.full((3, 1, 2, 3), np.nan, np.float32)
    tracked[2, 0] = [[0.5, -0.2, height], ahead]
    loaded = load_trajectory(dataclasses.replace(traj, tracked=tracked).save(tmp_path / "tracked.npz"))
    np.testing.assert_array_equal(loaded.tracked, tracked)
    overlays = Overlays(server.scene, loaded)
    assert overlays.available["tracked"]
    node = overlays.nodes["tracked"][0]
    overlays.update(1, np.zeros((0, 3)))
    assert not node.visible
    overlays.update(2, np.zeros((0, 3)))
    assert node.visible
    np.testing.assert_allclose(node.points, tracked[2, 0], atol=1e-6)
    overlays.set_visible("tracked", False)
    assert not node.visible
    overlays.remove()


def test_overlay_poses_turn_as_the_planner_and_the_urdf_read_them():
    """The path overlay's quaternions (scipy) are MuJoCo's of the planner's roll, pitch, yaw (up to sign), and the
    URDF writer's roll, pitch, yaw give the rotation back."""
    from legged.soccer.placo.urdf import _rpy
    from planners.body_check import quat_rpy, rotation_rpy
    from web.overlays import quat_from_rpy

    rpy = np.random.default_rng(0).uniform(-1.5, 1.5, (20, 3))
    mujoco_quats = np.array([quat_rpy(*angles) for angles in rpy])
    assert np.allclose(np.abs(np.sum(quat_from_rpy(rpy) * mujoco_quats, 1)), 1.0, atol=1e-12)
    assert np.allclose([_rpy(rotation_rpy(*angles)) for angles in rpy], rpy, atol=1e-12)
