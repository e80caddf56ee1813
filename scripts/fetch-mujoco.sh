#!/usr/bin/env bash
# Fetches the MuJoCo 3.17.0 shared library that graspd-sim links (mujoco-rs 7.0.0 expects exactly
# this version; docs/architecture.md) from the PyPI wheel into .tools/mujoco/, adds the
# unversioned name the linker looks for, and prints the folder. Idempotent.
set -euo pipefail

VERSION=3.17.0
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
DEST="$ROOT/.tools/mujoco"
"$ROOT/scripts/fetch-wheel-lib.sh" mujoco "$VERSION" "mujoco/libmujoco.so.$VERSION" "$DEST" >/dev/null
ln -sf "libmujoco.so.$VERSION" "$DEST/libmujoco.so"
echo "$DEST"
