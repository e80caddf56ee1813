#!/usr/bin/env bash
# Starts target/release/graspd on a free loopback port with the shared hands imported, runs
# `graspd-sim SUBCOMMAND ARGS...` against it (stabilize: the tactile closed loop under a
# disturbance), and stops the server. Called by `make sim-bench` and `make sim-stabilize`.
# `bench` with no further arguments is the standard run of docs/sim-benchmark.md, four hands,
# 20 trials per cell, placements within ±10 cm: the Table 5.2 objects from a single RGB-D view,
# all 13 shared objects from a single view, and the Table 5.2 objects from 3 fused views, into
# sim-results/{table-5-2,all-objects,fused-views}; `stabilize` with no further arguments runs the
# tactile closed loop twice (Eq 6.9 as printed, and with the session options that stop the drops);
# `clutter` reach-to-grasp in clutter into sim-results/clutter.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
hands="$root/../shared/testdata/hands"
. "$root/scripts/graspd-loopback.sh"
start_graspd \
    --import-hand robotiq_2f85="$hands/robotiq_2f85/2f85.xml" \
    --import-hand barrett_mjcf="$hands/barrett/wam_barrett_gripper.xml" \
    --import-hand shadow_mjcf="$hands/shadow_hand/right_hand.xml" \
    --import-hand allegro="$hands/wonik_allegro/right_hand.xml"
sim() {
    "$root/target/release/graspd-sim" --graspd "http://$addr" \
        --testdata "$root/../shared/testdata" "$@"
}
if [ "$#" -eq 1 ] && [ "$1" = bench ]; then
    sim bench --trials 20 --out sim-results/table-5-2
    sim bench --trials 20 --objects all --out sim-results/all-objects
    sim bench --trials 20 --views 3 --out sim-results/fused-views
elif [ "$#" -eq 1 ] && [ "$1" = stabilize ]; then
    # The tactile closed loop of docs/sim-benchmark.md: Eq 6.9 as printed, then with the
    # session's slip latch, slip from the contact centroid's motion and f_max = 6 f0.
    sim stabilize --hand robotiq_2f85 --trials 10 --seed 0 --out sim-results/stabilize-eq-6-9
    sim stabilize --hand robotiq_2f85 --trials 10 --seed 0 --latch-slip --centroid-slip 20 \
        --max-force 6 --out sim-results/stabilize
elif [ "$#" -eq 1 ] && [ "$1" = clutter ]; then
    # Reach-to-grasp in clutter (docs/sim-benchmark.md, Table 3.1's layout); one worker, so that
    # the request timings are graspd's own.
    sim clutter --trials 4 --jobs 1 --out sim-results/clutter
else
    sim "$@"
fi
