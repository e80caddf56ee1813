#!/usr/bin/env bash
# Installs the Python client (clients/python) with its test extras into .tools/pyclient-venv and
# runs its tests against target/debug/graspd (build it first: `cargo build --bins`).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="$root/.tools/pyclient-venv"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install -q --disable-pip-version-check -e "$root/clients/python[test]"
cd "$root/clients/python"
"$venv/bin/python" -m pytest -q
