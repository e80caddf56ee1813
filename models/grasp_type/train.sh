#!/usr/bin/env bash
# Reproducible training of the grasp-type network (models/grasp_type/MODEL_CARD.md): creates
# .tools/models-venv if missing, installs requirements.txt, builds gen-grasp-type-data, renders
# the train/val/test splits (seeds 1/2/3) into $GRASP_TYPE_DATA (default target/grasp_type_data),
# trains, exports grasp_type.onnx and checks it against PyTorch. Extra arguments go to train.py;
# with --data DIR (your own labelled frames, MODEL_CARD.md) nothing is generated:
#   models/grasp_type/train.sh --data my_frames/ --out my_model/
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
. "$here/../venv.sh"
models_venv "$here"
case " $* " in
*" --data "* | *" --data="*) exec nice "$py" "$here/train.py" "$@" ;;
esac
data="${GRASP_TYPE_DATA:-$root/target/grasp_type_data}"
(cd "$root" && cargo build --release -p graspd-model-data)
gen="$root/target/release/gen-grasp-type-data"
for split in "train 6000 1" "val 400 2" "test 600 3"; do
	read -r name count seed <<<"$split"
	if [ ! -f "$data/$name/meta.json" ]; then
		"$gen" --out "$data/$name" --count "$count" --seed "$seed" --previews 8
	fi
done
"$py" "$here/train.py" --self-check --test "$data/test"
exec nice "$py" "$here/train.py" --train "$data/train" --val "$data/val" \
	--test "$data/test" --out "$here" "$@"
