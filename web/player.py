"""Playback controls (play/pause, step, speed, loop, timeline) and the thread that advances the frame."""

from __future__ import annotations

import threading
import time
from typing import Callable

import viser


class Player:
    """Timeline of `num_frames` frames played at `speed` x real time; calls `on_frame(frame)` on every change."""

    def __init__(self, gui: viser.GuiApi, on_frame: Callable[[int], None], fps: float = 30.0):
        self._on_frame, self._fps = on_frame, fps
        self.dt, self.num_frames = 0.02, 1
        self.playing = False
        self._position = 0.0
        self._lock = threading.RLock()
        self.play_button = gui.add_button("Play", icon=viser.Icon.PLAYER_PLAY, hint="play or pause")
        self.step_buttons = gui.add_button_group("Step", ("|<", "<", ">", ">|"),
                                                 hint="first frame, one back, one forward, last frame")
        self.timeline = gui.add_slider("Timeline", 0, 1, 1, 0, hint="frame of the rollout; drag to scrub")
        self.speed = gui.add_slider("Speed", 0.1, 4.0, 0.1, 1.0, hint="playback speed, times real time")
        self.loop = gui.add_checkbox("Loop", True, hint="start again at the end")
        self.clock = gui.add_markdown("t = 0.00 s")
        self.play_button.on_click(lambda _: self.toggle())
        self.step_buttons.on_click(lambda event: self._step(event.target.value))
        self.timeline.on_update(self._scrubbed)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="dashboard-player", daemon=True)
        self._thread.start()

    def load(self, num_frames: int, dt: float) -> None:
        """A new trajectory: reset the timeline to frame 0 (keeps playing if it was)."""
        with self._lock:
            self.num_frames, self.dt = max(int(num_frames), 1), float(dt)
            self.timeline.max = max(self.num_frames - 1, 1)
            self._position = 0.0
            self._show(0, force=True)

    @property
    def frame(self) -> int:
        """The frame shown now."""
        return int(self.timeline.value)

    def toggle(self) -> None:
        """Play if paused, pause if playing; playing from the last frame starts again at frame 0."""
        with self._lock:
            self.playing = not self.playing
            if self.playing and self.frame >= self.num_frames - 1:
                self._position = 0.0
                self._show(0)
            self.play_button.label = "Pause" if self.playing else "Play"
            self.play_button.icon = viser.Icon.PLAYER_PAUSE if self.playing else viser.Icon.PLAYER_PLAY

    def _step(self, which: str) -> None:
        with self._lock:
            if self.playing:
                self.toggle()
            target = {"|<": 0, "<": self.frame - 1, ">": self.frame + 1, ">|": self.num_frames - 1}[which]
            target = min(max(target, 0), self.num_frames - 1)
            self._position = float(target)
            self._show(target)

    def _scrubbed(self, event) -> None:
        if event.client is None:
            return  # our own update of the slider
        with self._lock:
            value = min(int(self.timeline.value), self.num_frames - 1)
            self._position = float(value)
            self._show(value, force=True)

    def _show(self, frame: int, force: bool = False) -> None:
        if force or frame != int(self.timeline.value):
            self.timeline.value = frame
            self._on_frame(frame)
            self.clock.content = f"t = {frame * self.dt:.2f} s (frame {frame} of {self.num_frames - 1})"

    def _run(self) -> None:
        last = time.perf_counter()
        while not self._stop.wait(1.0 / self._fps):
            now = time.perf_counter()
            elapsed, last = now - last, now
            if not self.playing:
                continue
            with self._lock:
                self._position += elapsed * float(self.speed.value) / self.dt
                if self._position > self.num_frames - 1:
                    if self.loop.value:
                        self._position = 0.0
                    else:
                        self._position = float(self.num_frames - 1)
                        self.toggle()
                self._show(int(self._position))

    def close(self) -> None:
        """Stop the playback thread."""
        self._stop.set()
        self._thread.join(timeout=2.0)
