"""The example grasp dataset of ``mjtvm rank`` (docs/datasets.md): perturbed Shadow hand grasps.

Each grasp starts from models/shadow_hand/shadow_hand_coupled-sphere.toml (the Shadow hand
with J1 = J2 coupled beside its sum tendon, three fingertips on a sphere), or from the grasp
file ``--grasp FILE``, a grasp of a sphere: one that adds its sphere (``object.size``) and
closes the fingertips by IK (the Shadow files, e.g. the five-finger
shadow_hand_5f_coupled-sphere.toml), or one whose sphere is a body of its model, at a keyframe
or joint values (models/allegro/allegro-sphere.toml, models/leap_hand/leap_hand-sphere.toml):
there the file's configuration is the IK's start and every colliding geom of its
``[[contacts]]`` selections an IK target. The sphere's radius is scaled by a random factor in
[0.9, 1.1] (its mass by the cube, as ``mjtvm rank`` scales it: an added sphere in the document,
a model's sphere in the compiled model, by ``BatchModels`` as the ranking compiles it), its
centre moved by up to 4 mm along each axis, the IK's start joint values perturbed by up to
0.15 rad (the joints of a J1 = J2 equality of the file's model kept equal), and the IK closes
the fingertips onto the sphere. A grasp whose IK fails, or that touches the sphere with a geom
no contact selects, is drawn again. The last ``--broken`` grasps are made to fail on purpose,
half with one finger joint (``--break-joint``, default the Shadow's rh_FFJ3) opened by 0.1 rad
(a fingertip off the sphere: ``no contact``) and half closed by 0.1 rad (a fingertip inside it:
``penetration``), so that the dataset shows failure rows.

Stored per grasp (``.npz``): ``grasp_qpos`` (the hand's root's world pose: the one body under
the world besides the object, as ``mjtvm rank`` poses it; then the hand's joints in model
order: 13 for the default file, 22 for the five-finger one, 16 for the Allegro and the LEAP),
``obj_pose`` (the sphere's centre and orientation), ``obj_scale``, ``id``. The
random generator is seeded: the same command writes the same file.

With ``--mesh K`` the objects are K procedurally made mesh objects instead (written beside
the dataset, in ``<stem>-objects/``): an ellipsoid of semi-axes 25 mm times a random factor in
[0.85, 1.15] each, 0.08 kg, as two convex pieces (its upper and lower halves, each a mesh of
points on the surface: MuJoCo collides the convex hull), each grasp on one of them
(``obj_path``, scale 1), the fingertips closed onto it by the same IK.

Usage::

    python tools/make_rank_dataset.py                      # 36 grasps (4 broken)
    python tools/make_rank_dataset.py -n 240 --mesh 6 --out /tmp/mesh/big.npz  # mesh objects
    python tools/make_rank_dataset.py --grasp models/shadow_hand/shadow_hand_5f_coupled-sphere.toml \
        --out /tmp/5f.npz                                  # the five-finger hand, 36 LPs a grasp
    python tools/make_rank_dataset.py --grasp models/allegro/allegro-sphere.toml -n 240 --broken 0 \
        --seed 35 --out allegro240.npz                     # the Allegro's keyframe grasp, perturbed
"""

from __future__ import annotations

import argparse
import time
import tomllib
from pathlib import Path
from typing import NamedTuple

import mujoco
import numpy as np

from mjtvm.errors import ModelError
from mjtvm.grasp.document.document import read_grasp_document
from mjtvm.grasp.resolve.batch import BatchModels, hand_joints
from mjtvm.grasp.resolve.file import grasp_from_model, load_grasp
from mjtvm.grasp.resolve.loaded import Grasp
from mjtvm.grasp.resolve.model import geom_labels

ROOT = Path(__file__).resolve().parents[1]
GRASP = ROOT / "models" / "shadow_hand" / "shadow_hand_coupled-sphere.toml"
OUT = ROOT / "mjtvm" / "data" / "examples" / "shadow-sphere-dataset.npz"
#: The joint ``--broken`` opens or closes by 0.1 rad: the first finger's proximal flexion.
BREAK_JOINT = "rh_FFJ3"


def coupled_joints(model_file: str) -> list[tuple[str, str]]:
    """The (joint1, joint2) of each joint equality joint1 = joint2 (polycoef 0 1 0 0 0) of the
    model: the coupled J1 = J2 of a Shadow hand's fingers."""
    model = mujoco.MjModel.from_xml_path(model_file)
    pairs = []
    for e in range(model.neq):
        if int(model.eq_type[e]) != int(mujoco.mjtEq.mjEQ_JOINT) or not model.eq_active0[e]:
            continue
        if not np.array_equal(model.eq_data[e][:5], [0.0, 1.0, 0.0, 0.0, 0.0]):
            continue
        pairs.append((model.joint(model.eq_obj1id[e]).name, model.joint(model.eq_obj2id[e]).name))
    return pairs


_COUPLED: dict[str, list[tuple[str, str]]] = {}


class ModelSphere(NamedTuple):
    """A grasp file whose sphere is a body of its model (the Allegro's allegro-sphere.toml):
    the configuration (its keyframe or joint values) becomes the IK's start, the contact
    selections its targets, and the sphere is scaled in the model as ``mjtvm rank`` scales it.
    (A named tuple: the tests load this tool as a module outside ``sys.modules``, where a
    dataclass cannot resolve its annotations.)

    Parameters
    ----------
    start
        The hand's joint values of the file's configuration (rad), in model order.
    position
        The sphere's centre at that configuration (world frame, m), shape (3,).
    targets
        The IK targets: every colliding geom of each ``[[contacts]]`` selection, by label.
    """

    start: dict[str, float]
    position: tuple[float, float, float]
    targets: tuple[str, ...]


_MODEL_SPHERES: dict[str, ModelSphere] = {}


def model_sphere(doc: dict, file: Path) -> ModelSphere:
    """The :class:`ModelSphere` of a grasp document whose ``object.body`` is in its model."""
    grasp = load_grasp(doc)
    model, data, body = grasp.model, grasp.data, doc["object"]["body"]
    ob = model.body(body).id
    geoms = [g for g in range(model.ngeom) if int(model.geom_bodyid[g]) == ob]
    if len(geoms) != 1 or int(model.geom_type[geoms[0]]) != int(mujoco.mjtGeom.mjGEOM_SPHERE):
        raise SystemExit(
            f"{file}: object.body: {body!r} is not one sphere geom: the generator scales a sphere"
        )
    labels = geom_labels(model)
    targets = []
    for i, sel in enumerate(doc["contacts"]):
        if "geom" in sel:
            targets.append(sel["geom"])
        elif "body" in sel:
            b = model.body(sel["body"]).id
            targets += [
                labels[g]
                for g in range(model.ngeom)
                if int(model.geom_bodyid[g]) == b and (model.geom_contype[g] or model.geom_conaffinity[g])
            ]
        else:
            raise SystemExit(f"{file}: contacts[{i}]: select the IK target by geom or body")
    start = {j: float(data.qpos[model.joint(j).qposadr[0]]) for j in hand_joints(model, body)}
    x, y, z = (float(v) for v in data.xpos[ob])
    return ModelSphere(start, (x, y, z), tuple(targets))


def _document(rng: np.random.Generator, grasp: Path = GRASP) -> tuple[dict, float]:
    doc = tomllib.loads(grasp.read_text(encoding="utf-8"))
    doc["model"] = str(grasp.parent / doc["model"])
    if doc["model"] not in _COUPLED:
        _COUPLED[doc["model"]] = coupled_joints(doc["model"])
    scale = float(rng.uniform(0.9, 1.1))
    obj = dict(doc["object"])
    config = dict(doc["configuration"])
    if "size" in obj:  # the sphere added by the file: its size and mass scaled here
        obj["size"] = [obj["size"][0] * scale]
        obj["mass"] = obj["mass"] * scale**3
        ik = dict(config["ik"])
    else:  # the model's sphere: scaled when the model is compiled (make); the file's grasp closed by IK
        if doc["model"] not in _MODEL_SPHERES:
            _MODEL_SPHERES[doc["model"]] = model_sphere(doc, grasp)
        sphere = _MODEL_SPHERES[doc["model"]]
        obj["position"] = list(sphere.position)
        ik = {"targets": [{"geom": t} for t in sphere.targets], "start": dict(sphere.start)}
    obj["position"] = [float(x) for x in np.asarray(obj["position"]) + rng.uniform(-0.004, 0.004, 3)]
    ik["start"] = {k: v + float(rng.uniform(-0.15, 0.15)) for k, v in ik["start"].items()}
    for j1, j2 in _COUPLED[doc["model"]]:  # the coupled hand's J1 = J2: the start keeps them equal
        if j1 in ik["start"] and j2 in ik["start"]:
            ik["start"][j1] = ik["start"][j2]
    config = {"ik": ik}
    doc["object"], doc["configuration"] = obj, config
    return doc, scale


def root_body(model: mujoco.MjModel, object_body: str) -> str:
    """The hand's root: the one body under the world other than the object (as ``mjtvm rank``
    poses it, docs/datasets.md)."""
    ob = model.body(object_body).id
    roots = [b for b in range(1, model.nbody) if int(model.body_parentid[b]) == 0 and b != ob]
    if len(roots) != 1:
        raise SystemExit(
            f"the model has {len(roots)} bodies under the world besides the object: expected one"
        )
    return str(model.body(roots[0]).name)


def _load(doc: dict, scale: float) -> Grasp:
    """The grasp of a document: its object added by the file (already scaled), or the model's
    sphere scaled in the compiled model (``BatchModels``, as ``mjtvm rank`` compiles it)."""
    if "size" in doc["object"]:
        return load_grasp(doc)
    normal, _ = read_grasp_document(doc)
    batch = BatchModels(normal, None)
    return grasp_from_model(normal, None, batch.model(None, scale), Path(doc["model"]))


_PIECE = '<mesh name="{name}" vertex="{vertex}"/>'


def _ellipsoid_pieces(rng: np.random.Generator) -> list[str]:
    """Two ``<mesh>`` elements: the upper and lower halves of a random ellipsoid (points only)."""
    axes = 0.025 * rng.uniform(0.85, 1.15, 3)
    lat = np.linspace(0.0, np.pi / 2, 5)
    lon = np.linspace(0.0, 2 * np.pi, 12, endpoint=False)
    meshes = []
    for sign, name in ((1.0, "upper"), (-1.0, "lower")):
        pts = [[0.0, 0.0, sign * axes[2]]]
        for t in lat[:-1]:
            for p in lon:
                pts.append(
                    [
                        axes[0] * np.cos(t) * np.cos(p),
                        axes[1] * np.cos(t) * np.sin(p),
                        sign * axes[2] * np.sin(t),
                    ]
                )
        vertex = "  ".join(" ".join(f"{x:.6f}" for x in q) for q in pts)
        meshes.append(_PIECE.format(name=f"piece_{name}", vertex=vertex))
    return meshes


def _object_xml(meshes: list[str], include: str = "") -> str:
    """An MJCF of the object (body ``ball`` on a free joint, two 0.04 kg pieces), with the
    hand included when ``include`` names its file."""
    geoms = "".join(
        f'<geom name="piece_{n}" type="mesh" mesh="piece_{n}" mass="0.04"/>' for n in ("upper", "lower")
    )
    head = f'<include file="{include}"/>' if include else ""
    return (
        f'<mujoco model="ellipsoid">{head}<asset>{"".join(meshes)}</asset><worldbody>'
        f'<body name="ball"><freejoint name="ball"/>{geoms}</body></worldbody></mujoco>\n'
    )


def make(
    n: int,
    broken: int,
    seed: int,
    mesh: int = 0,
    folder: Path | None = None,
    grasp_file: Path = GRASP,
    break_joint: str = BREAK_JOINT,
) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    top = tomllib.loads(grasp_file.read_text(encoding="utf-8"))
    hand = str(grasp_file.parent / top["model"])
    if mesh and "size" not in top["object"]:
        raise SystemExit(f"{grasp_file}: --mesh needs a grasp file that adds its sphere (object.size)")
    prefix = "shadow" if grasp_file == GRASP else grasp_file.stem.split("-")[0]
    scenes: list[tuple[str, str]] = []  # (scene file for the IK, object file relative to the dataset)
    if mesh:
        assert folder is not None
        folder.mkdir(parents=True, exist_ok=True)
        for k in range(mesh):
            meshes = _ellipsoid_pieces(rng)
            (folder / f"ellipsoid{k}.xml").write_text(_object_xml(meshes))
            scene = folder / f"ellipsoid{k}-scene.xml"
            scene.write_text(_object_xml(meshes, hand))
            scenes.append((str(scene), f"{folder.name}/ellipsoid{k}.xml"))
    rows_path: list[str] = []
    rows: dict[str, list] = {"grasp_qpos": [], "obj_pose": [], "obj_scale": [], "id": []}
    tries = 0
    while len(rows["id"]) < n:
        tries += 1
        if tries > 5 * n:
            raise SystemExit(f"only {len(rows['id'])} of {tries} IK runs closed the grasp")
        doc, scale = _document(rng, grasp_file)
        if scenes:  # the mesh object in place of the sphere, at the sphere's place
            scene, relative = scenes[len(rows["id"]) % len(scenes)]
            doc["model"], scale = scene, 1.0
            doc["object"] = {"body": "ball", "position": doc["object"]["position"]}
        try:
            grasp = load_grasp(doc) if scenes else _load(doc, scale)
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
            if break_joint not in names:
                raise SystemExit(
                    f"--break-joint: {break_joint!r} is not a hand joint: one of {', '.join(names)}"
                )
            k = names.index(break_joint)
            joints[k] += -0.1 if kind == "open" else 0.1
        palm = model.body(root_body(model, doc["object"]["body"])).id
        ball = model.body(doc["object"]["body"]).id
        rows["grasp_qpos"].append(np.concatenate([data.xpos[palm], data.xquat[palm], joints]))
        rows["obj_pose"].append(np.concatenate([data.xpos[ball], data.xquat[ball]]))
        rows["obj_scale"].append(scale)
        if scenes:
            rows_path.append(relative)
        rows["id"].append(
            f"{prefix}-{'mesh' if scenes else 'sphere'}-{i:03d}" + ("" if kind == "ok" else f"-{kind}")
        )
    extra = {"obj_path": np.array(rows_path)} if scenes else {}
    return {
        **extra,
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
    parser.add_argument("--mesh", type=int, default=0, help="mesh objects (0: the sphere, scaled)")
    parser.add_argument("--grasp", type=Path, default=GRASP, help="the grasp file (default: %(default)s)")
    parser.add_argument(
        "--break-joint", default=BREAK_JOINT, help="the joint --broken moves (default: %(default)s)"
    )
    parser.add_argument("--out", type=Path, help=f"the dataset file (default with the default grasp: {OUT})")
    args = parser.parse_args()
    args.grasp = args.grasp.resolve()
    if args.out is None:
        if args.grasp != GRASP:
            parser.error("--out is required with --grasp (the default output is the shipped example's)")
        args.out = OUT
    t0 = time.perf_counter()
    folder = args.out.parent / f"{args.out.stem}-objects"
    arrays = make(args.n, args.broken, args.seed, args.mesh, folder, args.grasp, args.break_joint)
    np.savez_compressed(args.out, **arrays)
    print(
        f"wrote {args.out}: {args.n} grasps in {time.perf_counter() - t0:.1f} s, {args.out.stat().st_size} bytes"
    )


if __name__ == "__main__":
    main()
