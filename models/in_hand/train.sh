#!/usr/bin/env bash
# Reproducible training of the in-hand rotation policies (dissertation ch. 7, docs/in-hand.md):
# creates .tools/models-venv if missing, installs requirements.txt, builds graspd and graspd-sim
# (MuJoCo: scripts/fetch-mujoco.sh), starts graspd on a free loopback port (the Shadow's posture
# synergies for r_hand come from it), then trains the five algorithms of §7.5.2 (ppo, ppo_hand,
# ppo_unc, composite, marl) on the block and the egg for $IN_HAND_STEPS environment steps each
# (default 200,000: about 12 min a run, 2 h in all on two cores) into $IN_HAND_OUT (default
# target/in_hand; a run with a metrics.json is kept), and draws the learning curves into
# docs/in-hand/. IN_HAND_TASKS and IN_HAND_ALGOS (space-separated) narrow the set; extra
# arguments go to train.py.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
. "$here/../venv.sh"
models_venv "$here"
export MUJOCO_DYNAMIC_LINK_DIR="${MUJOCO_DYNAMIC_LINK_DIR:-$("$root/scripts/fetch-mujoco.sh" | tail -n 1)}"
export LD_LIBRARY_PATH="$MUJOCO_DYNAMIC_LINK_DIR:${LD_LIBRARY_PATH:-}"
(cd "$here" && "$py" -m pytest -q -p no:cacheprovider test_marl_ppo.py)
(cd "$root" && cargo build --release --bin graspd --bin graspd-sim)
. "$root/scripts/graspd-loopback.sh"
start_graspd
out="${IN_HAND_OUT:-$root/target/in_hand}"
for task in ${IN_HAND_TASKS:-block egg}; do
	for algo in ${IN_HAND_ALGOS:-ppo ppo_hand ppo_unc composite marl}; do
		run="$out/$task/$algo"
		[ -f "$run/metrics.json" ] && continue
		mkdir -p "$out/$task"
		echo "== $task $algo" >&2
		nice "$py" "$here/train.py" --sim "$root/target/release/graspd-sim" \
			--graspd "http://$addr" --testdata "$root/../shared/testdata" \
			--object "$task" --algo "$algo" --steps "${IN_HAND_STEPS:-200000}" \
			--out "$run" "$@" >"$run.log" 2>&1 || { tail -n 20 "$run.log"; exit 1; }
	done
done
"$py" "$here/plot.py" --runs "$out" --docs "$root/docs/in-hand"
