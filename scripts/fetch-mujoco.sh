#!/usr/bin/env bash
# Fetches the MuJoCo 3.17.0 shared library that graspd-sim links (mujoco-rs 7.0.0 expects exactly
# this version; docs/architecture.md) from the PyPI wheel into .tools/mujoco/ with the two names
# the linker and the loader look for, and prints the folder. Idempotent.
set -euo pipefail

VERSION=3.17.0
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
DEST="$ROOT/.tools/mujoco"
LIB="$DEST/libmujoco.so.$VERSION"

if [[ ! -f "$LIB" ]]; then
    TMP="$(mktemp -d)"
    trap 'rm -rf "$TMP"' EXIT
    echo "fetching mujoco $VERSION (PyPI wheel) into $DEST" >&2
    python3 -m pip download --quiet --no-deps --only-binary=:all: --python-version 3.11 \
        --platform manylinux_2_28_x86_64 "mujoco==$VERSION" -d "$TMP" >&2
    WHEEL="$(ls "$TMP"/mujoco-"$VERSION"-*.whl)"
    mkdir -p "$DEST"
    # Extract to a temporary name first so that an interrupted run leaves no partial library.
    python3 - "$WHEEL" "mujoco/libmujoco.so.$VERSION" "$LIB.part" <<'PY'
import shutil, sys, zipfile
wheel, member, out = sys.argv[1:]
with zipfile.ZipFile(wheel) as z, z.open(member) as src, open(out, "wb") as dst:
    shutil.copyfileobj(src, dst)
PY
    mv "$LIB.part" "$LIB"
fi
ln -sf "libmujoco.so.$VERSION" "$DEST/libmujoco.so"
echo "$DEST"
