"""Peers measured beside legged in the same benchmark run (MuJoCo Playground's Go1; dm_control's soccer is
legged.soccer.peer_dm_control). The Playground peer runs in its own virtual environment: see
playground.py and setup_playground.sh here, and `legged bench env --peer-python` in docs/cli.md."""
