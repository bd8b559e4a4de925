"""The example grasp dataset of ``mjtvm rank`` (docs/datasets.md): perturbed Shadow hand grasps.

Each grasp starts from models/shadow_hand/shadow_hand-sphere.toml (the tendon-coupled Shadow
hand, three fingertips on a sphere): the sphere's radius is scaled by a random factor in
[0.9, 1.1] (its mass by the cube, as ``mjtvm rank`` scales it), its centre moved by up to 4 mm
along each axis, the IK's start joint values perturbed by up to 0.15 rad, and the grasp file's
own IK closes the three fingertips onto the sphere. A grasp whose IK fails is drawn again. The
last ``--broken`` grasps are made to fail on purpose, half with one finger joint opened by
0.1 rad (a fingertip off the sphere: ``no contact``) and half closed by 0.1 rad (a fingertip
inside it: ``penetration``), so that the dataset shows failure rows.

Stored per grasp (``.npz``): ``grasp_qpos`` (the palm's world pose, then the 13 hand joints in
model order), ``obj_pose`` (the sphere's centre and orientation), ``obj_scale``, ``id``. The
random generator is seeded: the same command writes the same file.

Usage::

    python scripts/make_rank_dataset.py                      # 36 grasps (4 broken)
    python scripts/make_rank_dataset.py -n 240 --out big.npz # the acceptance's size
"""

from __future__ import annotations

import argparse
import time
import tomllib
from pathlib import Path

import numpy as np

from mjtvm.errors import ModelError
from mjtvm.sim.grasp.batch import hand_joints
from mjtvm.sim.grasp.file import load_grasp

ROOT = Path(__file__).resolve().parents[1]
GRASP = ROOT / "models" / "shadow_hand" / "shadow_hand-sphere.toml"
OUT = ROOT / "mjtvm" / "data" / "examples" / "shadow-sphere-dataset.npz"
ROOT_BODY = "rh_palm"


def _document(rng: np.random.Generator) -> tuple[dict, float]:
    doc = tomllib.loads(GRASP.read_text(encoding="utf-8"))
    doc["model"] = str(GRASP.parent / doc["model"])
    scale = float(rng.uniform(0.9, 1.1))
    obj = dict(doc["object"])
    obj["size"] = [obj["size"][0] * scale]
    obj["mass"] = obj["mass"] * scale**3
    obj["position"] = [float(x) for x in np.asarray(obj["position"]) + rng.uniform(-0.004, 0.004, 3)]
    config = dict(doc["configuration"])
    ik = dict(config["ik"])
    ik["start"] = {k: v + float(rng.uniform(-0.15, 0.15)) for k, v in ik["start"].items()}
    config["ik"] = ik
    doc["object"], doc["configuration"] = obj, config
    return doc, scale


def make(n: int, broken: int, seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    rows: dict[str, list] = {"grasp_qpos": [], "obj_pose": [], "obj_scale": [], "id": []}
    tries = 0
    while len(rows["id"]) < n:
        tries += 1
        if tries > 5 * n:
            raise SystemExit(f"only {len(rows['id'])} of {tries} IK runs closed the grasp")
        doc, scale = _document(rng)
        try:
            grasp = load_grasp(doc)
            grasp.check_contacts()
        except ModelError:
            continue
        model, data = grasp.model, grasp.data
        names = hand_joints(model, doc["object"]["body"])
        joints = np.array([data.qpos[model.joint(j).qposadr[0]] for j in names])
        i = len(rows["id"])
        kind = "ok"
        if i >= n - broken:  # a finger joint opened (off the sphere) or closed (into it)
            kind = "open" if (i - (n - broken)) % 2 == 0 else "closed"
            k = names.index("rh_FFJ3")
            joints[k] += -0.1 if kind == "open" else 0.1
        palm, ball = model.body(ROOT_BODY).id, model.body(doc["object"]["body"]).id
        rows["grasp_qpos"].append(np.concatenate([data.xpos[palm], data.xquat[palm], joints]))
        rows["obj_pose"].append(np.concatenate([data.xpos[ball], data.xquat[ball]]))
        rows["obj_scale"].append(scale)
        rows["id"].append(f"shadow-sphere-{i:03d}" + ("" if kind == "ok" else f"-{kind}"))
    return {
        "grasp_qpos": np.array(rows["grasp_qpos"]),
        "obj_pose": np.array(rows["obj_pose"]),
        "obj_scale": np.array(rows["obj_scale"]),
        "id": np.array(rows["id"]),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-n", type=int, default=36, help="grasps")
    parser.add_argument("--broken", type=int, default=4, help="grasps made to fail (the last ones)")
    parser.add_argument("--seed", type=int, default=24)
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    t0 = time.perf_counter()
    arrays = make(args.n, args.broken, args.seed)
    np.savez_compressed(args.out, **arrays)
    print(
        f"wrote {args.out}: {args.n} grasps in {time.perf_counter() - t0:.1f} s, {args.out.stat().st_size} bytes"
    )


if __name__ == "__main__":
    main()
