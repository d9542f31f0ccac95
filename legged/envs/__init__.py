"""Legged-robot environments (Brax API) on MJX or native MuJoCo. Build one with `legged.tasks.make(task)`."""
