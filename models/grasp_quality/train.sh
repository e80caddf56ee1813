#!/usr/bin/env bash
# Reproducible training of the learned parallel-jaw grasp quality
# (models/grasp_quality/MODEL_CARD.md): creates .tools/models-venv if missing, installs
# requirements.txt, builds graspd-sim (MuJoCo: scripts/fetch-mujoco.sh), labels 3,000 scenes × 8
# sampled Robotiq 2F-85 grasps by executing each in MuJoCo (`graspd-sim label-grasps`, seeds
# 0..3000, about 27 min on 2 cores) into $GRASP_LABELS (default target/grasp_labels/run1),
# trains, exports grasp_quality.onnx and checks it against PyTorch. Extra arguments go to
# train.py.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
. "$here/../venv.sh"
models_venv "$here"
data="${GRASP_LABELS:-$root/target/grasp_labels/run1}"
export MUJOCO_DYNAMIC_LINK_DIR="${MUJOCO_DYNAMIC_LINK_DIR:-$("$root/scripts/fetch-mujoco.sh" | tail -n 1)}"
export LD_LIBRARY_PATH="$MUJOCO_DYNAMIC_LINK_DIR:${LD_LIBRARY_PATH:-}"
(cd "$root" && cargo build --release -p graspd-sim)
if [ ! -f "$data/label.npy" ]; then
	"$root/target/release/graspd-sim" --testdata "$root/../shared/testdata" label-grasps \
		--scenes 3000 --per-scene 8 --seed 0 --out "$data"
fi
nice "$py" "$here/train.py" --data "$data" --out "$here" "$@"
