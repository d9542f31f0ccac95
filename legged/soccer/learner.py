"""One player's view of a soccer game: the single-agent environment the training backends see.

The learner controls agent 0 (home0, attacking +x). Every other robot (in 2v2 the learner's teammate too)
acts from an `Opponent` passed to `step` as data (a frozen self-play snapshot, the placo player or the
standing script); without one the standing script plays. With a `Walker` (legged.soccer.walker) the learner
and the network opponents command velocities (3 actions) that the frozen walking skill turns into joints.
Observations, reward and per-term metrics are agent 0's; the game's statistics are reported from the
learner's side (goals_for, goals_against).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from brax.envs.base import State

from legged.envs.api import MjxEnv, layout_slices
from legged.envs.math import yaw_rotate
from legged.envs.physics import PhysicsView, Spawn
from legged.sensors.native_raycam import render_anywhere
from legged.soccer.env import SoccerEnv
from legged.soccer.observe import PROPRIO_SIZE, feature_layout, read_bodies
from legged.soccer.opponents import (Opponent, OpponentNet, ball_pan, network_actions, opponent_step,
                                     scripted_opponent)
from legged.soccer.placo.player import load_tables
from legged.soccer.vision.cameras import soccer_camera
from legged.soccer.vision.estimates import estimate_parts, squared_errors
from legged.soccer.vision.sightings import SIGHTED, SIGHTING_SIZE
from legged.soccer.vision.tracker import (TRACKER_INPUT_SIZE, tracked_features, tracked_pose, tracker_inputs,
                                          tracker_kickoff, tracker_sight, tracker_start, tracker_step)
from legged.soccer.walker import COMMAND_SIZE, Walker, getting_up

LEARNER = 0
"""Agent index the learner controls."""
HEAD_PAN = 0
"""Index of the head pan joint in the OP3's joint actions (RobotSpec.joint_names)."""
TRACKED_ARROW_M = 0.3
"""Length of the tracked heading drawn by viewers (`tracked_points`), metres."""


class LearnerView(MjxEnv):
    """Agent 0 of `game` as a Brax-style single-agent environment; `step(state, action, opponent=None)`
    (the opponent drives every other robot; None: the script). With `walker` the actions are velocity
    commands (legged.soccer.walker); with `teacher_prior` (vision games) the observations also hold
    `command_prior`, the placo player's command (from the true state) as actions, which a state teacher's
    corrections add to (a student that estimates the game does not read it; its teacher's labels do).

    A vision player whose walker adds the placo command (`command_prior=placo`) cannot read the ball and goals
    that command is computed from; it estimates them (`estimates_world`): its actions are [corrections to the
    placo command (3), its estimate of the game features after the proprioception (`world_size`: ball, goals,
    other players, as legged.soccer.observe.game_features)], and the placo command is computed from its
    proprioception and that estimate."""

    def __init__(self, game: SoccerEnv, net: OpponentNet = OpponentNet(), hidden: tuple[int, ...] = (),
                 walker: Walker | None = None, teacher_prior: bool = False):
        if teacher_prior and (walker is None or not game.config.vision):
            raise ValueError("teacher_prior (the placo command a vision student's teacher corrected) needs a walker "
                             "and a vision game")
        if walker is not None and abs(walker.dt - game.dt) > 1e-9:  # its gait clock would run at the wrong speed
            raise ValueError(f"the walker was trained with env.ctrl_dt={walker.dt:g}; this game steps every "
                             f"{game.dt:g} s: set env.ctrl_dt={walker.dt:g}")
        if walker is not None and walker.velocity_input and not game.config.velocity_in_state:
            raise ValueError("the walker reads a torso velocity estimate (it was trained with env.velocity_in_state): "
                             "set env.velocity_in_state=true so that the game keeps one")
        self.estimates_world = walker is not None and walker.prior is not None and game.config.vision
        if game.config.vision_gaze and not self.estimates_world:
            raise ValueError("vision_gaze turns the head toward the player's own estimate of the ball: it needs a "
                             "vision player that estimates the game (a walker with the placo prior: "
                             "soccer.command_prior=placo)")
        if game.config.vision_tracker and not self.estimates_world:
            raise ValueError("vision_tracker replaces parts of a vision player's estimate of the game by what it "
                             "tracks: it needs a player that estimates the game (soccer.command_prior=placo)")
        if game.camera is not None:  # the learner's observations need its own camera only
            game.camera = game.camera.select([LEARNER])
        self.game, self.net, self.walker, self.teacher_prior = game, net, walker, teacher_prior
        self.config, self.robot = game.config, game.robot
        self.mj_model = game.mj_model
        self.default_opponent = scripted_opponent(game.policy_state_size, self.player_action_size, hidden)
        self.estimate_parts = estimate_parts(game.layout.players_per_team)
        """Positions of the learner's estimate whose errors are reported (`estimates_world`)."""
        self._world_parts = layout_slices(feature_layout(game.layout.players_per_team)[1:])
        unknown = sorted(set(game.config.estimate_oracle) - set(self._world_parts))
        if game.config.estimate_oracle and (not self.estimates_world or unknown):
            raise ValueError(f"estimate_oracle replaces parts of a game-estimating vision player's estimate "
                             f"(soccer.command_prior=placo) by the truth; parts are {', '.join(self._world_parts)}"
                             + (f" (unknown: {', '.join(unknown)})" if unknown else ""))
        team = int(game.layout.team[LEARNER])
        goals = np.asarray(game._goals[:, :2], np.float32)[[team, 1 - team]]  # own, opponent
        self._goal_xy = goals
        """World x, y of the learner's own and the opponent goal's mouths [2, 2] (the tracker's pitch)."""
        self._net_xy = goals + np.stack([np.sign(goals[:, 0]) * game.config.scene.goal_depth, np.zeros(2)], -1)
        """... and of the centres of their back nets (what the camera sights)."""
        self.tables = load_tables()
        """The placo player's walk and kick (legged.soccer.placo.player)."""
        self._camera = None
        self.state_pilot: Opponent | None = None
        """A state player's network (an Opponent) that steers a game-estimating vision player from its estimate
        (`steer_with`); None: the player's own corrections do."""
        self.pilot_name = ""
        """What `state_pilot` is (e.g. its run directory), for reports; '' without one."""

    def steer_with(self, pilot: Opponent, name: str = "") -> None:
        """Let the state player `pilot` (a soccer-1v1 run whose commands correct the placo player's, as an
        Opponent) steer this vision player: its command is the pilot's at [proprioception, the player's
        estimate of the game], so the vision network only has to see (the player's own corrections are unused).
        Set before the first step is compiled."""
        if not self.estimates_world:
            raise ValueError("a state pilot steers from a vision player's estimate of the game: it needs a player "
                             "that estimates the game (soccer.command_prior=placo)")
        width = PROPRIO_SIZE + self.world_size
        if pilot.mean.shape[-1] != width:
            raise ValueError(f"the pilot reads {pilot.mean.shape[-1]} features, this player's proprioception and "
                             f"estimate are {width}")
        self.state_pilot, self.pilot_name = pilot, name or "a state player"

    def camera_images(self, data) -> jax.Array:
        """RGB image of the learner's head camera, [H, W, 3] uint8 (the ray renderer at the task's camera
        size), for viewers; jittable. Available in every soccer task, with or without vision."""
        if self._camera is None:
            self._camera = soccer_camera(self.mj_model, self.config.camera, self.game.layout)
        return render_anywhere(self._camera, data)["rgb"][LEARNER]

    # ----------------------------------------------------------------- engine verbs (reset, step: MjxEnv)
    def spawn(self, rng: jax.Array, carry: dict | None = None) -> Spawn:
        return self.game.spawn(rng, carry)

    def first_state(self, view: PhysicsView, info: dict, rng: jax.Array) -> State:
        game = self.game.first_state(view, info, rng)
        if self.estimates_world:  # running sums of its estimate's squared errors, and of their steps
            zeros = jnp.zeros(len(self.estimate_parts) + 1)  # the parts, then the ball when near
            game = game.replace(info=dict(game.info, estimate_sq=zeros, estimate_steps=zeros))
        if self.config.vision_tracker:  # near its kick-off spot, turned anyhow: the yaw is unknown until it sees
            start = tracker_start(self.game._kickoff[LEARNER])
            game = game.replace(info=dict(game.info, tracker=self._sight(start, game.info)))
        return self._view(game)

    def prepare(self, state: State, action: jax.Array, opponent: Opponent | None = None,
                teammate: Opponent | None = None):
        """Controls of every robot: the learner's action, the other team's from `opponent` (default: the
        script), the learner's teammates' (2v2) from `teammate` (default: `opponent`); the actions
        `transition` sees carry the players' memories and walker states along."""
        opponent = self.default_opponent if opponent is None else opponent
        mine, walker_state = self.learner_actions(state, action)
        others = state.info["game_obs"]["privileged_state"][LEARNER + 1:, :self.game.policy_state_size]
        memory = state.info["players"][LEARNER + 1:]
        theirs = None if self.walker is None else walker_state[LEARNER + 1:]
        velocity = state.info.get("velocity_estimate")
        velocity = None if velocity is None else velocity[LEARNER + 1:]
        step = lambda who: opponent_step(self.net, who, others, memory, self.tables, self.robot.action_scale,
                                         self.walker, theirs, velocity)
        played, moved, stepped = step(opponent)
        if teammate is not None:
            mate = jnp.asarray(self.game.layout.team[LEARNER + 1:] == self.game.layout.team[LEARNER])[:, None]
            mates = step(teammate)
            played, moved = jnp.where(mate, mates[0], played), jnp.where(mate, mates[1], moved)
            stepped = None if stepped is None else jnp.where(mate, mates[2], stepped)
        if stepped is not None:
            walker_state = walker_state.at[LEARNER + 1:].set(stepped)
        actions = jnp.concatenate([mine[None], played])
        memory = state.info["players"].at[LEARNER + 1:].set(moved)
        return (self.game.servo_controls(state, self.game.joint_targets(actions)),
                (actions, memory, walker_state, self._estimate_sq(state, action)))

    def learner_actions(self, state: State, action: jax.Array) -> tuple[jax.Array, jax.Array]:
        """(the learner's joint actions (20,), every robot's walker state with the learner's stepped): its
        action itself, or with a walker the walker's joint actions for its command."""
        walker_state = state.info["walker_state"]
        if self.walker is None:
            return action, walker_state
        features = state.info["game_obs"]["state"][LEARNER:LEARNER + 1]
        proprio = features[:, :PROPRIO_SIZE]
        if self.estimates_world:  # the placo command from what it sees, not from the truth
            estimate = self.used_estimate(state, action)
            action, features = action[:COMMAND_SIZE], jnp.concatenate([proprio, estimate[None]], -1)
            if self.state_pilot is not None:  # the state player's corrections at the estimated state
                action = network_actions(self.net, self.state_pilot, features)[0]
        mine = walker_state[LEARNER:LEARNER + 1]
        action = self.walker.with_prior(action[None], features)[0]
        velocity = state.info.get("velocity_estimate")
        joints = self.walker.actions(proprio, action[None], mine,
                                     None if velocity is None else velocity[LEARNER:LEARNER + 1])[0]
        if self.config.vision_gaze:  # look toward the ball it estimates (the ball's x, y lead the features)
            pan = ball_pan(features[0, PROPRIO_SIZE:PROPRIO_SIZE + 2]) / self.robot.action_scale
            joints = joints.at[HEAD_PAN].set(jnp.where(getting_up(mine[0]), joints[HEAD_PAN], pan))
        return joints, walker_state.at[LEARNER].set(self.walker.step(mine, action[None], proprio)[0])

    @property
    def player_action_size(self) -> int:
        """A player's actions (the opponents'): its joints, or with a walker a velocity command."""
        return COMMAND_SIZE if self.walker is not None else self.game.action_size

    @property
    def world_size(self) -> int:
        """Length of the learner's estimate of the game features among its actions (0 unless `estimates_world`)."""
        return self.game.policy_state_size - PROPRIO_SIZE if self.estimates_world else 0

    def used_estimate(self, state: State, action: jax.Array) -> jax.Array:
        """The game features (`world_size`) the learner's placo command is computed from (`estimates_world`): its
        estimate among its `action`, with the ball where the camera sees it under `vision_sighted_ball` and the
        parts named in `estimate_oracle` true."""
        world = action[COMMAND_SIZE:]
        if self.config.vision_tracker:
            parts = self._world_parts
            world = tracked_features(state.info["tracker"], world, parts["ball"], parts["own_goal"],
                                     parts["opponent_goal"], self._goal_xy[0], self._goal_xy[1],
                                     self.config.vision_ball_memory_s,
                                     parts["ball_vel"] if self.config.vision_ball_velocity else None)
        if self.config.vision_sighted_ball:
            sighting = self._sightings(state.info)[0]  # the ball's: seen, then x, y, z
            ball = self.estimate_parts["ball"]
            world = world.at[ball].set(jnp.where(sighting[0] > 0, sighting[1:], world[ball]))
        truth = state.info["game_obs"]["features"][LEARNER, PROPRIO_SIZE:]
        for name in self.config.estimate_oracle:  # diagnostics: the truth for these parts
            world = world.at[self._world_parts[name]].set(truth[self._world_parts[name]])
        return world

    def estimate_points(self, state: State, action: jax.Array) -> jax.Array:
        """World positions [4, 3] of what the learner's `action` estimates (`estimates_world`): the ball, its own
        goal, the opponent goal and the first other player (its teammate in 2v2), the last three on the ground;
        jittable."""
        world = self.used_estimate(state, action)
        ego = jnp.stack([world[part][:2] for part in self.estimate_parts.values()])
        xy, height = self._in_world(state, ego)
        z = jnp.array([height + world[2], 0.0, 0.0, 0.0])
        return jnp.concatenate([xy, z[:, None]], -1)

    def sighting_points(self, state: State) -> jax.Array:
        """World positions [3, 3] of what the learner's camera sights (`vision_sightings`: the ball, its own goal's
        net, the opponent goal's net), NaN where not in view; jittable."""
        sight = self._sightings(state.info)
        xy, height = self._in_world(state, sight[:, 1:3])
        points = jnp.concatenate([xy, height + sight[:, 3:]], -1)
        return jnp.where(sight[:, :1] > 0, points, jnp.nan)

    def tracked_points(self, state: State) -> jax.Array:
        """World positions [2, 3] of where the learner's tracker (`vision_tracker`) puts its torso and of a point
        TRACKED_ARROW_M ahead of it along the tracked heading, at the torso's height; NaN before it locks on."""
        pose, locked = tracked_pose(state.info["tracker"])
        ahead = pose[:2] + TRACKED_ARROW_M * jnp.stack([jnp.cos(pose[2]), jnp.sin(pose[2])])
        height = self._in_world(state, jnp.zeros((1, 2)))[1]
        points = jnp.concatenate([jnp.stack([pose[:2], ahead]), jnp.full((2, 1), height)], -1)
        return jnp.where(locked, points, jnp.nan)

    def _sightings(self, info: dict) -> jax.Array:
        """The learner's sightings in a state's `info` (`vision_sightings` or `vision_tracker`), [len(SIGHTED),
        SIGHTING_SIZE]."""
        return info["sightings"][LEARNER].reshape(len(SIGHTED), SIGHTING_SIZE)

    def _in_world(self, state: State, ego: jax.Array) -> tuple[jax.Array, jax.Array]:
        """(world x, y [k, 2] of points `ego` [k, 2] in the learner's heading frame, the learner's torso height)."""
        b = read_bodies(self.game.layout, state.pipeline_state.qpos, state.pipeline_state.qvel)
        return b.pos[LEARNER, :2] + yaw_rotate(-b.yaw[LEARNER], ego), b.pos[LEARNER, 2]

    @property
    def action_size(self) -> int:
        """The learner's actions: a player's, then its estimate of the game features (`estimates_world`)."""
        return self.player_action_size + self.world_size

    def _estimate_sq(self, state: State, action: jax.Array) -> tuple[jax.Array, jax.Array] | None:
        """(squared errors (metres^2), steps counted) of the learner's estimate (`estimates_world`) of each of
        `estimate_parts`, then of the ball when it is near (legged.soccer.vision.estimates.squared_errors)."""
        if not self.estimates_world:
            return None
        truth = state.info["game_obs"]["features"][LEARNER, PROPRIO_SIZE:]
        return squared_errors(self.used_estimate(state, action), truth, self.estimate_parts)

    def transition(self, state: State, view: PhysicsView, actions) -> State:
        actions, memory, walker_state, estimate_sq = actions
        info = dict(state.info, players=memory, walker_state=walker_state)
        if estimate_sq is not None:
            sq, steps = estimate_sq
            info.update(estimate_sq=info["estimate_sq"] + sq, estimate_steps=info["estimate_steps"] + steps)
        game_obs = info.pop("game_obs")
        game = State(view, game_obs, jnp.zeros(self.game.n_agents), state.done, {}, info)
        game = self.game.transition(game, view, actions)
        if self.config.vision_tracker:
            game = game.replace(info=dict(game.info, tracker=self._tracked(state, game, walker_state)))
        return self._view(game)

    def _tracked(self, state: State, game: State, walker_state: jax.Array) -> jax.Array:
        """The learner's tracker one control period on (`vision_tracker`): moved by its walking command and gyro
        over the period, back on its kick-off spot after a goal, corrected by what its camera now sights."""
        proprio = state.info["game_obs"]["state"][LEARNER, :PROPRIO_SIZE]
        up = -proprio[:3] / jnp.maximum(jnp.linalg.norm(proprio[:3]), 1e-6)  # gravity in the torso frame leads
        mine = walker_state[LEARNER]
        tracker = tracker_step(state.info["tracker"], mine[1:3], jnp.dot(proprio[3:6], up), getting_up(mine),
                               self.game.dt, self.config.vision_ball_velocity)
        kickoff = jnp.any(game.info["score"] != state.info["score"])
        tracker = jnp.where(kickoff, tracker_kickoff(self.game._kickoff[LEARNER]), tracker)
        return self._sight(tracker, game.info)

    def _sight(self, tracker: jax.Array, info: dict) -> jax.Array:
        """The learner's tracker corrected by its camera's sightings in the game's `info`."""
        return tracker_sight(tracker, self._sightings(info), self._net_xy, self.config.scene.goal_width,
                             self.config.vision_ball_velocity)

    def observation_layout(self) -> dict:
        layout = self.game.observation_layout()
        if self.config.vision_tracker_inputs:  # the learner's state ends with what its tracker knows
            layout = dict(layout, state=layout["state"] + [("tracker", TRACKER_INPUT_SIZE)])
        return layout

    @property
    def uses_cameras(self) -> bool:
        return self.game.uses_cameras

    @property
    def native_ray_camera(self):
        return self.game.native_ray_camera

    @property
    def mjx_model(self):
        return self.game.mjx_model

    def mjx_model_for(self, info: dict):
        return self.game.mjx_model_for(info)

    def native_model_fields(self, info: dict, rows):
        return self.game.native_model_fields(info, rows)

    def mjx_settle(self, model, data):
        return self.game.mjx_settle(model, data)

    def _view(self, game: State) -> State:
        """Agent 0's share of a game State (the whole game's observations kept in info for the others)."""
        metrics = {k: v[LEARNER] if v.ndim else v for k, v in game.metrics.items()
                   if k not in ("goals_home", "goals_away")}
        metrics.update(goals_for=game.metrics["goals_home"], goals_against=game.metrics["goals_away"])
        if self.estimates_world:  # root mean square over the episode so far (0 before any step counted)
            steps = game.info["estimate_steps"]
            rms = jnp.sqrt(game.info["estimate_sq"] / jnp.maximum(steps, 1.0))
            metrics.update({f"estimate_{name}_m": rms[k] for k, name in enumerate([*self.estimate_parts, "ball_near"])})
            metrics["estimate_ball_near_steps"] = steps[-1]  # to pool ball_near over episodes
        info = {**game.info, "game_obs": game.obs}
        obs = {k: v[LEARNER] for k, v in game.obs.items()}
        if self.config.vision_tracker_inputs:
            inputs = tracker_inputs(game.info["tracker"], self._goal_xy[0], self._goal_xy[1],
                                    self.config.vision_ball_memory_s)
            obs["state"] = jnp.concatenate([obs["state"], inputs])
        if self.teacher_prior:  # what the teacher's corrections were added to, from the state it reads
            obs["command_prior"] = self.walker.prior_actions(obs["features"][None], self.tables)[0]
        return State(game.pipeline_state, obs, game.reward[LEARNER], game.done, metrics, info)
