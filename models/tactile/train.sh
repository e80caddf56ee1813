#!/usr/bin/env bash
# Reproducible training of the tactile detector (models/tactile/MODEL_CARD.md):
# creates .tools/models-venv if missing, installs requirements.txt, measures the calibration
# statistics (when ../shared/testdata/tactile exists), generates data, trains, exports
# tactile_detector.onnx and checks it against PyTorch. Extra arguments go to train.py, e.g.
#   models/tactile/train.sh --data my_recordings/ --tare raw
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
venv="${MODELS_VENV:-$root/.tools/models-venv}"
if [ ! -x "$venv/bin/python" ]; then
	python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet -r "$here/requirements.txt"
cd "$here"
if [ "$#" -eq 0 ]; then
	nice "$venv/bin/python" calibrate.py
	# The shipped model: every 2nd window of 1000 generated sequences (MODEL_CARD.md).
	exec nice "$venv/bin/python" train.py --subsample 2
fi
exec nice "$venv/bin/python" train.py "$@"
