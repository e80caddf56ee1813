#!/usr/bin/env python3
"""Records MuJoCo's forward kinematics of the shared hands as the reference for graspd's FK tests.

What it writes: ``service/core/tests/fixtures/fk_reference.json`` with, for each hand in
``../shared/testdata/hands`` (Shadow, Allegro, Robotiq 2F-85, Barrett):

- ``file``: the MJCF path relative to the shared test-data ``hands`` folder;
- ``joints``: every hinge/slide joint in MuJoCo's qpos order with its type and limits as MuJoCo
  compiled them (radians for hinges, metres for slides; ``null`` when unlimited);
- ``bodies``: every body name except MuJoCo's ``world`` (``xpos`` rows follow this order);
- ``sites``: every site name;
- ``samples``: ``COUNT`` joint configurations drawn uniformly inside the limits (``[-pi, pi]`` for
  an unlimited hinge) with a seeded NumPy generator, each with ``qpos`` and, after
  ``mujoco.mj_kinematics``, the world-frame position of every body (``xpos``) and every site
  (``site_xpos``), in metres, rounded to 1e-9 m.

All joints are set independently. The Robotiq 2F-85 couples its 8 joints through 3 equality
constraints and a tendon, and the Shadow hand couples J1/J2 of four fingers through tendons; those
couplings act in the dynamics (mj_step), not in mj_kinematics, so FK of a full qpos is well defined
and is what graspd's FK must reproduce. The samples therefore include configurations that violate
the couplings; that is intended.

How to run (from the workspace root; needs network access to PyPI once):

    python3 -m venv .tools/mujoco-venv
    .tools/mujoco-venv/bin/pip install mujoco==3.17.0
    .tools/mujoco-venv/bin/python scripts/fk_reference.py [--testdata ../shared/testdata] [--count 20]

``.tools`` is git-ignored. The test ``service/core/tests/kinematics.rs`` reads the fixture.
"""

import argparse
import json
import math
import os
import sys

HANDS = [
    ("shadow_hand", "shadow_hand/right_hand.xml"),
    ("wonik_allegro", "wonik_allegro/right_hand.xml"),
    ("robotiq_2f85", "robotiq_2f85/2f85.xml"),
    ("barrett", "barrett/wam_barrett_gripper.xml"),
]
SEED = 20261106


def rounded(values):
    return [round(float(v), 9) for v in values]


def record(mujoco, np, path, count, rng):
    model = mujoco.MjModel.from_xml_path(path)
    data = mujoco.MjData(model)
    hinge, slide = int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)
    joints = []
    for j in range(model.njnt):
        kind = int(model.jnt_type[j])
        if kind not in (hinge, slide):
            raise SystemExit(f"{path}: joint {j} is neither hinge nor slide; extend the script")
        limited = bool(model.jnt_limited[j])
        joints.append(
            {
                "name": model.joint(j).name,
                "type": "hinge" if kind == hinge else "slide",
                "qposadr": int(model.jnt_qposadr[j]),
                "range": rounded(model.jnt_range[j]) if limited else None,
            }
        )
    bodies = [model.body(b).name for b in range(1, model.nbody)]
    sites = [model.site(s).name for s in range(model.nsite)]
    samples = []
    for _ in range(count):
        qpos = np.array(model.qpos0)
        for j in joints:
            lo, hi = j["range"] if j["range"] is not None else (-math.pi, math.pi)
            qpos[j["qposadr"]] = rng.uniform(lo, hi)
        data.qpos[:] = qpos
        mujoco.mj_kinematics(model, data)
        samples.append(
            {
                "qpos": rounded(qpos),
                "xpos": [rounded(data.xpos[b]) for b in range(1, model.nbody)],
                "site_xpos": [rounded(data.site_xpos[s]) for s in range(model.nsite)],
            }
        )
    return {"joints": joints, "bodies": bodies, "sites": sites, "samples": samples}


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--testdata", default=os.path.join(root, "..", "shared", "testdata"))
    parser.add_argument("--count", type=int, default=20)
    parser.add_argument(
        "--out", default=os.path.join(root, "service", "core", "tests", "fixtures", "fk_reference.json")
    )
    args = parser.parse_args()
    import mujoco
    import numpy as np

    rng = np.random.default_rng(SEED)
    hands_dir = os.path.join(args.testdata, "hands")
    out = {
        "generator": "scripts/fk_reference.py",
        "mujoco": mujoco.__version__,
        "seed": SEED,
        "hands": {},
    }
    for name, rel in HANDS:
        out["hands"][name] = {"file": rel, **record(mujoco, np, os.path.join(hands_dir, rel), args.count, rng)}
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w") as f:
        json.dump(out, f, separators=(",", ":"))
        f.write("\n")
    print(f"wrote {args.out} ({os.path.getsize(args.out)} bytes)", file=sys.stderr)


if __name__ == "__main__":
    main()
