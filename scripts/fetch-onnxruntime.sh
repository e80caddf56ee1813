#!/usr/bin/env bash
# Fetches the ONNX Runtime shared library that graspd loads at run time (ort's `load-dynamic`;
# docs/architecture.md, "Verified on this machine kind") into .tools/onnxruntime/ and prints its
# path. Idempotent.
#
# The library comes from the PyPI wheel (manylinux_2_28, needs only glibc and libstdc++), not
# from ort's build-time download, which fails offline and pins another version.
set -euo pipefail

VERSION=1.31.1
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
exec "$ROOT/scripts/fetch-wheel-lib.sh" onnxruntime "$VERSION" \
    "onnxruntime/capi/libonnxruntime.so.$VERSION" "$ROOT/.tools/onnxruntime"
