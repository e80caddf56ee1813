#!/usr/bin/env bash
# Usage: fetch-wheel-lib.sh PACKAGE VERSION MEMBER DEST
# Extracts the shared library MEMBER (a path inside the wheel, e.g. mujoco/libmujoco.so.3.17.0)
# from the manylinux_2_28 x86_64 PyPI wheel PACKAGE==VERSION into the folder DEST, under its own
# file name, and prints the library's path. Idempotent: does nothing but print the path when the
# library is already there. Used by fetch-onnxruntime.sh and fetch-mujoco.sh; pip only downloads
# (no install, no dependencies), so it works wherever PyPI is reachable.
set -euo pipefail

PACKAGE="$1" VERSION="$2" MEMBER="$3" DEST="$4"
LIB="$DEST/$(basename "$MEMBER")"

if [[ ! -f "$LIB" ]]; then
    TMP="$(mktemp -d)"
    trap 'rm -rf "$TMP"' EXIT
    echo "fetching $PACKAGE $VERSION (PyPI wheel) into $DEST" >&2
    python3 -m pip download --quiet --no-deps --only-binary=:all: --python-version 3.11 \
        --platform manylinux_2_28_x86_64 "$PACKAGE==$VERSION" -d "$TMP" >&2
    WHEEL="$(ls "$TMP"/"$PACKAGE"-"$VERSION"-*.whl)"
    mkdir -p "$DEST"
    # Extract to a temporary name first so that an interrupted run leaves no partial library.
    python3 - "$WHEEL" "$MEMBER" "$LIB.part" <<'PY'
import shutil, sys, zipfile
wheel, member, out = sys.argv[1:]
with zipfile.ZipFile(wheel) as z, z.open(member) as src, open(out, "wb") as dst:
    shutil.copyfileobj(src, dst)
PY
    mv "$LIB.part" "$LIB"
fi
echo "$LIB"
