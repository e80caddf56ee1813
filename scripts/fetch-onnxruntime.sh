#!/usr/bin/env bash
# Fetches the ONNX Runtime shared library that graspd loads at run time (ort's `load-dynamic`;
# docs/architecture.md, "Verified on this machine kind") into .tools/onnxruntime/ and prints its
# path. Idempotent: does nothing but print the path when the library is already there.
#
# The library comes from the PyPI wheel (manylinux_2_28, needs only glibc and libstdc++), not
# from ort's build-time download, which fails offline and pins another version.
set -euo pipefail

VERSION=1.31.1
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
DEST="$ROOT/.tools/onnxruntime"
LIB="$DEST/libonnxruntime.so.$VERSION"

if [[ ! -f "$LIB" ]]; then
    TMP="$(mktemp -d)"
    trap 'rm -rf "$TMP"' EXIT
    echo "fetching onnxruntime $VERSION (PyPI wheel) into $DEST" >&2
    python3 -m pip download --quiet --no-deps --only-binary=:all: --python-version 3.11 \
        --platform manylinux_2_28_x86_64 "onnxruntime==$VERSION" -d "$TMP" >&2
    WHEEL="$(ls "$TMP"/onnxruntime-"$VERSION"-*.whl)"
    mkdir -p "$DEST"
    # Extract to a temporary name first so that an interrupted run leaves no partial library.
    python3 - "$WHEEL" "onnxruntime/capi/libonnxruntime.so.$VERSION" "$LIB.part" <<'PY'
import shutil, sys, zipfile
wheel, member, out = sys.argv[1:]
with zipfile.ZipFile(wheel) as z, z.open(member) as src, open(out, "wb") as dst:
    shutil.copyfileobj(src, dst)
PY
    mv "$LIB.part" "$LIB"
fi
echo "$LIB"
