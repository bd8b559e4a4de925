"""Sample datasets of every layout ``mjtvm rank`` reads (docs/datasets.md), nothing downloaded.

The grasps are the coupled Shadow hand's of ``tools/make_rank_dataset.py`` (the grasp file's IK
closing three fingertips onto an object), written in each pipeline's own layout:

* ``dexgraspbench/``: DexGraspBench's tree (``src/task/convert_format.py``):
  ``assets/object/<object>/urdf/meshes/convex_piece_00<k>.obj`` (an ellipsoid of random
  semi-axes as two convex pieces, normalised: the grasp's size is ``obj_scale`` times it) and
  ``output/shadow/graspdata/<object>/scale<NNN>_pose000/<i>.npy``, one pickled dict per grasp:
  ``obj_path`` (relative to the tree's root, as the benchmark writes it), ``obj_pose``,
  ``obj_scale``, ``grasp_qpos``, ``pregrasp_qpos`` (the flexion joints opened by 0.1 rad) and
  ``squeeze_qpos`` (closed by 0.02 rad);
* ``dexgraspnet/shadow-sphere.npy``: DexGraspNet's per-object list of dicts
  (``grasp_generation/main.py``): ``scale`` and ``qpos`` by joint name with the palm's
  ``WRJT*`` (m) and ``WRJR*`` (static x-y-z Euler angles, rad) in the object's frame;
* ``shadow-sphere.npz`` and ``shadow-sphere.csv``: the same sphere grasps in mjtvm's own keys.

Seeded: the same command writes the same files. Usage::

    python tools/make_dataset_samples.py --out tests/data/datasets          # the committed ones
    python tools/make_dataset_samples.py --objects 5 --scales 4 --per 20 --out /tmp/bench  # 400
"""

from __future__ import annotations

import argparse
import csv
import sys
import tempfile
import tomllib
from pathlib import Path

import numpy as np
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).resolve().parent))
from make_rank_dataset import GRASP, ROOT_BODY, _document, make

from mjtvm.errors import ModelError
from mjtvm.grasp.resolve.batch import hand_joints
from mjtvm.grasp.resolve.file import load_grasp

_FLEX = ("J1", "J2", "J3")  # the flexion joints opened for the pregrasp, closed for the squeeze


def _write_obj(path: Path, points: np.ndarray) -> None:
    hull = ConvexHull(points)
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in points]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in hull.simplices]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n")


def _halves(axes: np.ndarray) -> list[np.ndarray]:
    lat = np.linspace(0.0, np.pi / 2, 5)
    lon = np.linspace(0.0, 2 * np.pi, 12, endpoint=False)
    out = []
    for sign in (1.0, -1.0):
        pts = [[0.0, 0.0, sign * axes[2]]]
        for t in lat[:-1]:
            pts += [
                [axes[0] * np.cos(t) * np.cos(p), axes[1] * np.cos(t) * np.sin(p), sign * axes[2] * np.sin(t)]
                for p in lon
            ]
        out.append(np.array(pts))
    return out


def _scene(pieces: list[Path], scale: float, path: Path) -> None:
    """An IK scene: the hand and the object at this scale (body ``ball``)."""
    meshes = "".join(
        f'<mesh name="p{k}" file="{p.resolve()}" scale="{scale} {scale} {scale}"/>'
        for k, p in enumerate(pieces)
    )
    geoms = "".join(f'<geom type="mesh" mesh="p{k}" mass="0.04"/>' for k in range(len(pieces)))
    hand = GRASP.parent / "shadow_right_3f_coupled.xml"
    path.write_text(
        f'<mujoco model="scene"><include file="{hand}"/><asset>{meshes}</asset><worldbody>'
        f'<body name="ball"><freejoint name="ball"/>{geoms}</body></worldbody></mujoco>\n'
    )


def _bench(out: Path, objects: int, scales: int, per: int, seed: int) -> int:
    rng = np.random.default_rng(seed)
    root = out / "dexgraspbench"
    scenes = Path(tempfile.mkdtemp())  # the IK's scenes, not part of the sample
    count = 0
    for k in range(objects):
        name = f"ellipsoid_{k:02d}"
        folder = root / "assets" / "object" / name
        pieces = [folder / "urdf" / "meshes" / f"convex_piece_{i:03d}.obj" for i in range(2)]
        for piece, pts in zip(pieces, _halves(0.25 * rng.uniform(0.85, 1.15, 3)), strict=True):
            _write_obj(piece, pts)
        for s in range(scales):
            scale = round(0.09 + 0.01 * s, 3)
            scene = scenes / f"{name}-{s}.xml"
            _scene(pieces, scale, scene)
            grasps = (
                root / "output" / "shadow" / "graspdata" / name / f"scale{round(scale * 100):03d}_pose000"
            )
            grasps.mkdir(parents=True, exist_ok=True)
            i = tries = 0
            while i < per:
                tries += 1
                if tries > 5 * per + 5:
                    raise SystemExit(f"{name} scale {scale}: only {i} of {tries} IK runs closed the grasp")
                doc, _ = _document(rng)
                doc["model"] = str(scene)
                doc["object"] = {"body": "ball", "position": doc["object"]["position"]}
                try:
                    grasp = load_grasp(doc)
                    grasp.check_contacts()
                except ModelError:
                    continue
                model, data = grasp.model, grasp.data
                names = hand_joints(model, "ball")
                joints = np.array([data.qpos[model.joint(j).qposadr[0]] for j in names])
                flex = np.array([n.endswith(_FLEX) for n in names])
                palm, ball = model.body(ROOT_BODY).id, model.body("ball").id
                base = np.concatenate([data.xpos[palm], data.xquat[palm]])
                lo, hi = model.jnt_range[[model.joint(j).id for j in names]].T
                np.save(
                    grasps / f"{i}.npy",
                    {
                        "obj_pose": np.concatenate([data.xpos[ball], data.xquat[ball]]),
                        "obj_scale": np.float64(scale),
                        "obj_path": f"assets/object/{name}",
                        "pregrasp_qpos": np.concatenate([base, np.clip(joints - 0.1 * flex, lo, hi)]).astype(
                            np.float32
                        ),
                        "grasp_qpos": np.concatenate([base, joints]).astype(np.float32),
                        "squeeze_qpos": np.concatenate([base, np.clip(joints + 0.02 * flex, lo, hi)]).astype(
                            np.float32
                        ),
                    },
                    allow_pickle=True,
                )
                i += 1
                count += 1
    return count


def _sphere(out: Path, n: int, seed: int) -> None:
    rows = make(n, 0, seed)
    np.savez(out / "shadow-sphere.npz", **rows)
    size = rows["grasp_qpos"].shape[1]
    with (out / "shadow-sphere.csv").open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(
            [f"grasp_qpos_{i}" for i in range(size)]
            + [f"obj_pose_{i}" for i in range(7)]
            + ["obj_scale", "id"]
        )
        for g, p, s, i in zip(
            rows["grasp_qpos"], rows["obj_pose"], rows["obj_scale"], rows["id"], strict=True
        ):
            w.writerow([repr(float(x)) for x in g] + [repr(float(x)) for x in p] + [repr(float(s)), str(i)])
    doc = tomllib.loads(GRASP.read_text(encoding="utf-8"))
    doc["model"] = str(GRASP.parent / doc["model"])
    names = hand_joints(load_grasp(doc).model, "ball")
    items = []
    for g, p, s in zip(rows["grasp_qpos"], rows["obj_pose"], rows["obj_scale"], strict=True):
        # DexGraspNet's frame: the object at the origin, unrotated (the sphere's own rotation is
        # immaterial; its centre becomes the origin).
        euler = Rotation.from_quat([g[4], g[5], g[6], g[3]]).as_euler("xyz")  # extrinsic: sxyz
        qpos = {n: float(v) for n, v in zip(names, g[7:], strict=True)}
        qpos.update(dict(zip(("WRJTx", "WRJTy", "WRJTz"), (float(x) for x in g[:3] - p[:3]), strict=True)))
        qpos.update(dict(zip(("WRJRx", "WRJRy", "WRJRz"), (float(x) for x in euler), strict=True)))
        items.append({"scale": float(s), "qpos": qpos, "energy": 0.0})
    (out / "dexgraspnet").mkdir(exist_ok=True)
    np.save(out / "dexgraspnet" / "shadow-sphere.npy", np.array(items, dtype=object), allow_pickle=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--objects", type=int, default=2, help="DexGraspBench objects")
    parser.add_argument("--scales", type=int, default=1, help="scales per object")
    parser.add_argument("--per", type=int, default=2, help="grasps per object and scale")
    parser.add_argument(
        "--sphere", type=int, default=3, help="grasps of the .npz, .csv and DexGraspNet samples"
    )
    parser.add_argument("--seed", type=int, default=34)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    n = _bench(args.out, args.objects, args.scales, args.per, args.seed)
    _sphere(args.out, args.sphere, args.seed)
    print(f"wrote {n} DexGraspBench grasps and {args.sphere} sphere grasps under {args.out}")


if __name__ == "__main__":
    main()
