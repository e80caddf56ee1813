#!/usr/bin/env bash
# Reproducible training of the tactile detector (models/tactile/MODEL_CARD.md):
# creates .tools/models-venv if missing, installs requirements.txt, measures the calibration
# statistics (when ../shared/testdata/tactile exists), generates data, trains, exports
# tactile_detector.onnx and checks it against PyTorch. Extra arguments go to train.py, e.g.
#   models/tactile/train.sh --data my_recordings/ --tare raw
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
. "$here/../venv.sh"
models_venv "$here"
cd "$here"
if [ "$#" -eq 0 ]; then
	nice "$py" calibrate.py
	# The shipped model: every 2nd window of 1000 generated sequences (MODEL_CARD.md).
	exec nice "$py" train.py --subsample 2
fi
exec nice "$py" train.py "$@"
