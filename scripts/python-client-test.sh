#!/usr/bin/env bash
# Installs the Python client (clients/python) with its test extras into .tools/pyclient-venv and
# runs its tests against target/debug/graspd (build it first: `cargo build --bins`).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="$root/.tools/pyclient-venv"
# The server loads its built-in grasp-type model through ONNX Runtime, as under `make test`.
if [ -z "${ORT_DYLIB_PATH:-}" ]; then
  for lib in "$root"/.tools/onnxruntime/libonnxruntime.so.*; do
    [ -f "$lib" ] && export ORT_DYLIB_PATH="$lib" && break
  done
fi
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install -q --disable-pip-version-check -e "$root/clients/python[test]"
cd "$root/clients/python"
"$venv/bin/python" -m pytest -q
