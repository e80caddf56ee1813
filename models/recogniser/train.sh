#!/usr/bin/env bash
# Reproducible training of the recogniser (models/recogniser/MODEL_CARD.md): creates
# .tools/models-venv if missing, installs requirements.txt, builds gen-recogniser-data, renders
# the train/val/test splits (seeds 11/12/13; the test split with the unseen chips can) into
# $RECOGNISER_DATA (default target/recogniser_data), trains, exports recogniser.onnx and checks
# it against PyTorch, then measures detection by name on 500 more held-out scenes (seed 21, with
# the unseen chips can) through graspd's own code (eval-recogniser, MODEL_CARD.md). Extra
# arguments go to train.py.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
. "$here/../venv.sh"
models_venv "$here"
data="${RECOGNISER_DATA:-$root/target/recogniser_data}"
(cd "$root" && cargo build --release -p graspd-model-data)
gen="$root/target/release/gen-recogniser-data"
for split in "train 3000 11" "val 300 12" "test 500 13 --unseen"; do
	read -r name count seed extra <<<"$split"
	if [ ! -f "$data/$name/meta.json" ]; then
		"$gen" --out "$data/$name" --scenes "$count" --seed "$seed" $extra
	fi
done
nice "$py" "$here/train.py" --train "$data/train" --val "$data/val" \
	--test "$data/test" --out "$here" "$@"
# eval-recogniser runs the model through graspd's ONNX Runtime.
export ORT_DYLIB_PATH="${ORT_DYLIB_PATH:-$("$root/scripts/fetch-onnxruntime.sh" | tail -n 1)}"
"$root/target/release/eval-recogniser" --model "$here/recogniser.onnx" --scenes 500 --seed 21 \
	--unseen | tee "$here/detection.json"
