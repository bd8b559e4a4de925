"""An object made of convex mesh pieces (models/objects/allegro-jenga: six pieces of a scanned
Jenga tower's published convex decomposition in the Allegro hand), through every command.

The model is checked against its source (mesh geoms, convex pieces, a few dozen vertices); the
grasp's contact Jacobians against central finite differences of the finger-fixed contact
points; its alphas against the independent cvxpy transcription; the lift keeps its F-points on
the object's pieces while it moves the object by its body pose; and each of ``export-state``,
``solve``, ``tvms``, ``replay`` and ``verify`` runs on it as a subprocess. The accuracy of the
contact normals on meshes (docs/grasp-format.md, "Mesh objects") is measured on an icosphere.
"""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest
from scipy.spatial import ConvexHull

import mjtvm
from mjtvm.grasp.resolve.file import load_grasp, shipped_grasps
from mjtvm.grasp.resolve.loaded import Grasp
from mjtvm.grasp.resolve.state import detected_contacts, geom_id
from oracles.reference import reference_tvmmp
from tests.support.finite_diff import contact_jacobians_fd

NAME = "allegro-jenga"
PIECES = ("jenga_piece3", "jenga_piece9", "jenga_piece10", "jenga_piece11", "jenga_piece13", "jenga_piece15")


@pytest.fixture(scope="module")
def grasp() -> Grasp:
    return load_grasp(NAME)


def _mesh_vertices(model: mujoco.MjModel, g: int) -> np.ndarray:
    k = int(model.geom_dataid[g])
    v0, n = int(model.mesh_vertadr[k]), int(model.mesh_vertnum[k])
    return np.array(model.mesh_vert[v0 : v0 + n], dtype=float)


def test_the_object_is_six_convex_mesh_pieces_cited_from_their_source(grasp: Grasp) -> None:
    model = grasp.model
    ob = model.body("jenga").id
    geoms = [g for g in range(model.ngeom) if int(model.geom_bodyid[g]) == ob]
    assert [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) for g in geoms] == list(PIECES)
    assert all(int(model.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_MESH) for g in geoms)
    total = 0
    for g in geoms:
        verts = _mesh_vertices(model, g)
        total += len(verts)
        assert len(ConvexHull(verts).vertices) == len(verts)  # convex: every vertex on its hull
    assert total == 74
    text = shipped_grasps()[NAME].with_name("allegro_jenga.xml").read_text(encoding="utf-8")
    assert "kevinzakka/mujoco_scanned_objects" in text and "3783d450f636c797406c39038453355d7a88a692" in text
    assert "CC-BY 4.0" in text
    # the fingertips touch two different pieces (the IK found the nearest surfaces)
    touched = {
        min(PIECES, key=lambda p: mujoco.mj_geomDistance(model, grasp.data, model.geom(p).id, g, 1.0, None))
        for g in (geom_id(model, f"{tip}_tip/geom1") for tip in ("ff", "mf", "rf", "th"))
    }
    assert touched == {"jenga_piece3", "jenga_piece13"}


def test_grasp_jacobians_match_finite_differences(grasp: Grasp) -> None:
    """Each contact's (3, M) Jacobian = d(finger-fixed contact point)/dq, central differences."""
    state = grasp.state()
    assert len(state.contacts) == 4
    fd = contact_jacobians_fd(grasp.model, grasp.data.qpos, state)
    for contact in state.contacts:
        np.testing.assert_allclose(contact.jacobian, fd[contact.name], atol=1e-8, err_msg=contact.name)


def test_contacts_lie_on_the_mesh_surface_with_unit_normals_into_it(grasp: Grasp) -> None:
    state = grasp.state()
    model, data = grasp.model, grasp.data
    for contact in state.contacts:
        g = geom_id(model, contact.name.split("#")[0])
        near = min(mujoco.mj_geomDistance(model, data, model.geom(p).id, g, 1.0, None) for p in PIECES)
        assert abs(near) < 1e-7, contact.name
        assert np.linalg.norm(contact.normal) == pytest.approx(1.0, abs=1e-12)
        tip = data.geom_xpos[g]  # a fingertip sphere: the normal into the object points away from it
        assert float(contact.normal @ (contact.position - tip)) > 0.0


def test_grasp_alphas_match_the_cvxpy_reference(grasp: Grasp) -> None:
    state = grasp.state()
    result = mjtvm.tvmmp(state)
    alpha, _status = reference_tvmmp(state, solver="HIGHS")
    np.testing.assert_allclose(np.asarray(result.alpha, dtype=float), alpha, rtol=1e-6, atol=1e-8)
    assert result.tvmmp is not None and result.tvmmp > 0.01  # the four fingertips hold and move it


def test_lift_moves_the_object_by_its_body_pose_and_keeps_the_f_points() -> None:
    """4 cm along -x (the grasp file's lift): the object's body moves by exactly that, every
    F-point stays on its object-fixed point (within 1e-8 m from step to step; the start, an
    IK pose, within its 1e-6 m tolerance) and on a piece's surface."""
    from mjtvm.lift.states import lift_state
    from mjtvm.lift.trajectory import scripted_lift

    lift = scripted_lift(NAME, num_states=3)
    model = lift.scenario.model
    data = mujoco.MjData(model)
    ob = model.body("jenga").id
    start: dict[str, np.ndarray] = {}
    origin0 = None
    for i in range(lift.num_states):
        data.qpos[:] = lift.qpos[i]
        mujoco.mj_kinematics(model, data)
        rot, pos = data.xmat[ob].reshape(3, 3), np.array(data.xpos[ob])
        origin0 = pos if origin0 is None else origin0
        np.testing.assert_allclose(pos - origin0, [-lift.s[i], 0.0, 0.0], atol=1e-12)
        for g, role, p in zip(lift.geoms, lift.roles, lift.points[i], strict=True):
            assert role == "F"
            local = rot.T @ (p - pos)
            if i == 0:  # the grasp file's IK pose (tolerance 1e-6 m): the point within that
                start[g] = local
                continue
            assert np.linalg.norm(local - start[g]) < (1e-6 if i == 1 else 1e-8), (i, g)
            start[g] = local
            gid = geom_id(model, g)
            gap = min(mujoco.mj_geomDistance(model, data, model.geom(q).id, gid, 1.0, None) for q in PIECES)
            assert abs(gap) < 1e-7, (i, g, gap)
        # the start is the grasp file's IK pose (tolerance 1e-6 m); the lift's own steps: 1e-8
        assert np.all(lift.residual[i] < (1e-6 if i == 0 else 1e-8))
        assert len(lift_state(lift, i).contacts) == 4
    assert lift.s[-1] == pytest.approx(0.04, abs=1e-12)


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    proc = subprocess.run(
        [sys.executable, "-m", "mjtvm.cli", *args], capture_output=True, text=True, check=False
    )
    assert proc.returncode == 0, proc.stderr
    return proc


def test_export_state_solve_and_tvms_on_the_command_line() -> None:
    state = json.loads(_run("export-state", NAME).stdout)
    assert state["schema"] == "mjtvm.state/1" and len(state["contacts"]) == 4
    result = json.loads(_run("solve", NAME, "--no-witnesses").stdout)
    assert result["feasible"] and 0.01 < result["tvmmp"] < 1.0  # m/s
    assert all(s == "optimal" for row in result["status"] for s in row)
    tvms = json.loads(_run("tvms", NAME, "--quiet").stdout)
    # the RVDS are the six translations: the TVMS is 3-D and bounded, and (one REFS vertex) the
    # velocity alpha_l r_l of Problem 2 lies on its boundary: in it, and 1e-6 farther out not
    assert tvms["status"] == "bounded" and tvms["dimension"] == 3 and tvms["affine_volume"] > 0
    vertices = np.asarray(tvms["vertices"], dtype=float)
    assert np.all(vertices[:, 3:] == 0.0)
    hull = ConvexHull(vertices[:, :3])
    alpha = np.asarray(result["alpha"], dtype=float)[0]
    rvds = np.asarray(json.loads(_run("export-state", NAME).stdout)["rvds"], dtype=float)[:, :3]
    for a, r in zip(alpha, rvds, strict=True):
        slack = hull.equations[:, :3] @ (a * r) + hull.equations[:, 3]
        assert (
            np.max(slack) < 1e-9
            and np.max(hull.equations[:, :3] @ ((1 + 1e-6) * a * r) + hull.equations[:, 3]) > 0
        )


def test_replay_and_verify_on_the_command_line(tmp_path: Path) -> None:
    out = tmp_path / "replay"
    _run(
        "replay", "--grasp", NAME, "--states", "3", "--no-sweeps", "--no-plots", "--quiet", "--out", str(out)
    )
    with (out / "lift.csv").open(encoding="utf-8") as f:
        rows = [r for r in csv.DictReader(f) if r["variant"] == "L"]
    assert [float(r["s"]) for r in rows] == pytest.approx([0.0, 0.02, 0.04], abs=1e-12)
    assert all(r["feasible"] == "True" and float(r["tvmmp"]) > 0.01 for r in rows)
    out = tmp_path / "verify"
    _run(
        "verify", "--grasp", NAME, "--states", "2", "--stride", "2", "--contacts", "L",
        "--reading", "physical", "--no-plots", "--quiet", "--out", str(out),
    )  # fmt: skip
    with (out / "verify.csv").open(encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 12  # 2 states x 6 RVDS directions
    ratios = np.array([float(r["ratio"]) for r in rows])
    # the simulated hand reaches most of the LP's speed (measured: median 0.98; one pair fails
    # its twist check at the end of the lift)
    assert np.median(ratios) > 0.9


# ---------------------------------------------------------------- normals on meshes (measured)
def _icosphere(level: int) -> np.ndarray:
    """Unit-sphere vertices of an icosahedron whose triangles are split in four ``level`` times
    (12, 42, 162, ... vertices); each new vertex is an edge midpoint pushed onto the sphere."""
    t = (1 + 5**0.5) / 2
    base: list[tuple[float, float, float]] = [
        (-1, t, 0),
        (1, t, 0),
        (-1, -t, 0),
        (1, -t, 0),
        (0, -1, t),
        (0, 1, t),
    ]
    base += [(0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [np.array(p, dtype=float) / np.linalg.norm(p) for p in base]
    faces: list[tuple[int, int, int]] = [
        (int(a), int(b), int(c)) for a, b, c in ConvexHull(np.array(v)).simplices
    ]
    for _ in range(level):
        index: dict[tuple[int, int], int] = {}
        for a, b, c in faces:
            for e in ((a, b), (b, c), (c, a)):
                key = (min(e), max(e))
                if key not in index:
                    m = v[e[0]] + v[e[1]]
                    index[key] = len(v)
                    v.append(m / np.linalg.norm(m))
        split: list[tuple[int, int, int]] = []
        for a, b, c in faces:
            ab, bc, ca = (
                index[(min(a, b), max(a, b))],
                index[(min(b, c), max(b, c))],
                index[(min(c, a), max(c, a))],
            )
            split += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = split
    return np.array(v)


def test_mesh_normals_are_the_polytope_normals_not_the_smooth_surface() -> None:
    """A 35 mm sphere as a 162-vertex mesh, a 12 mm fingertip sphere touching it from 200 random
    directions: the contact normal (:func:`detected_contacts`) is the polytope's exact normal
    (facet, edge or vertex: the direction from the hull's nearest point, computed here from
    MuJoCo's float32 vertices) to 1e-6 rad (measured: 2.1e-8 rad), and differs from the analytic
    sphere's normal by the tessellation (measured: median 3.7 deg, max 7.6 deg; bounded by the
    largest angle between a facet's normal and its corners' radial directions, 10.8 deg)."""
    radius, tip = 0.035, 0.012
    verts = radius * _icosphere(2)
    xml = f"""<mujoco><asset><mesh name="m" vertex="{" ".join(f"{x:.17g}" for x in verts.ravel())}"/></asset>
    <worldbody><body name="object"><freejoint/><geom type="mesh" mesh="m"/></body>
    <body name="tip" mocap="true"><geom type="sphere" size="{tip}"/></body></worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)  # the object at rest: its mesh as MuJoCo stores it (float32)
    rot = np.array(data.geom_xmat[0]).reshape(3, 3)
    float32 = _mesh_vertices(model, 0) @ rot.T + np.array(data.geom_xpos[0])
    hull = ConvexHull(float32)
    rng = np.random.default_rng(7)
    off_polytope, off_sphere = [], []
    for _ in range(200):
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        lo, hi = 0.0, radius + tip + 0.01  # the centre distance at which the tip touches (bisection)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            data.mocap_pos[0] = mid * u
            mujoco.mj_kinematics(model, data)
            lo, hi = (mid, hi) if mujoco.mj_geomDistance(model, data, 0, 1, 1.0, None) < 0 else (lo, mid)
        data.mocap_pos[0] = hi * u
        (found,) = detected_contacts(model, data, object_body="object", tolerance=1e-4)
        outward = -found.normal
        centre = hi * u
        # the exact normal: from the hull's nearest point to the tip's centre (the nearest point
        # of a convex polytope: the best of its facets' projections, clipped to the facet)
        nearest = _nearest_on_hull(hull, float32, centre)
        exact = (centre - nearest) / np.linalg.norm(centre - nearest)
        off_polytope.append(float(np.arccos(np.clip(outward @ exact, -1.0, 1.0))))
        off_sphere.append(float(np.degrees(np.arccos(np.clip(outward @ u, -1.0, 1.0)))))
    assert max(off_polytope) < 1e-6
    # the tessellation: a facet's normal is off the sphere's radial direction at its corners by
    # the angle below, and the contact's normal lies between neighbouring facets' normals
    corners = max(
        float(np.degrees(np.arccos(np.clip(e[:3] @ (p / np.linalg.norm(p)), -1.0, 1.0))))
        for e, tri in zip(hull.equations, hull.simplices, strict=True)
        for p in float32[tri]
    )
    assert 2.0 < float(np.median(off_sphere)) < 6.0 and max(off_sphere) <= corners + 1e-6


def _nearest_on_hull(hull: ConvexHull, points: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The point of the convex hull nearest to ``x`` (outside it): the nearest point over its
    triangles (each triangle's nearest point, by its barycentric region)."""
    best, best_d = None, np.inf
    for tri in hull.simplices:
        a, b, c = points[tri]
        p = _nearest_on_triangle(a, b, c, x)
        d = float(np.linalg.norm(p - x))
        if d < best_d:
            best, best_d = p, d
    assert best is not None
    return best


def _nearest_on_triangle(a: np.ndarray, b: np.ndarray, c: np.ndarray, p: np.ndarray) -> np.ndarray:
    # Ericson, Real-Time Collision Detection, 5.1.5 (closest point on a triangle)
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = ab @ ap, ac @ ap
    if d1 <= 0 and d2 <= 0:
        return a
    bp = p - b
    d3, d4 = ab @ bp, ac @ bp
    if d3 >= 0 and d4 <= d3:
        return b
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        return a + ab * (d1 / (d1 - d3))
    cp = p - c
    d5, d6 = ab @ cp, ac @ cp
    if d6 >= 0 and d5 <= d6:
        return c
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        return a + ac * (d2 / (d2 - d6))
    va = d3 * d6 - d5 * d4
    if va <= 0 and (d4 - d3) >= 0 and (d5 - d6) >= 0:
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))
    denom = 1.0 / (va + vb + vc)
    return a + ab * (vb * denom) + ac * (vc * denom)


# ------------------------------------------------ an L finger passing from one piece to the next
def _box_as_two_mesh_pieces(tmp_path: Path, split: float) -> Path:
    """models/gripper3/gripper3.xml with its box object (half-sizes 50, 25, 30 mm) replaced by two
    convex mesh pieces that fill the same box, cut at ``split`` (m, the object's frame)."""
    source = shipped_grasps()["gripper3-box"].with_name("gripper3.xml")
    text = source.read_text(encoding="utf-8")
    box = '<geom name="object" type="box" size="0.05 0.025 0.03" mass="0.2" material="object" friction="0.8 0.01 0.0001"/>'
    assert box in text

    def cuboid(z0: float, z1: float) -> str:
        corners = [(x, y, z) for x in (-0.05, 0.05) for y in (-0.025, 0.025) for z in (z0, z1)]
        return " ".join(f"{c:.17g}" for p in corners for c in p)

    pieces = (
        f'<geom name="lower" type="mesh" mesh="lower" mass="{0.2 * (split + 0.03) / 0.06!r}" material="object" '
        'friction="0.8 0.01 0.0001"/>'
        f'<geom name="upper" type="mesh" mesh="upper" mass="{0.2 * (0.03 - split) / 0.06!r}" material="object" '
        'friction="0.8 0.01 0.0001"/>'
    )
    assets = (
        f'<mesh name="lower" vertex="{cuboid(-0.03, split)}"/><mesh name="upper" vertex="{cuboid(split, 0.03)}"/>'
        "</asset>"
    )
    text = text.replace(box, pieces).replace("</asset>", assets, 1)
    path = tmp_path / "gripper3_pieces.xml"
    path.write_text(text, encoding="utf-8")
    return path


def test_an_l_finger_slides_from_one_mesh_piece_onto_the_next(tmp_path: Path) -> None:
    """gripper3-box's lift (3 cm up; the middle finger an L-point sliding 3 cm down the box's
    -y face, relative to the box) with the box made of two mesh pieces cut 5 mm below the box's
    centre: the L finger passes from the upper piece onto the lower one at s = 15 mm. The
    object's surface is the box's, so the lift is the box's lift: the same joint values and
    contact points within 1e-7 (the pieces' vertices are float32), and from the first state
    off the table the same alphas."""
    import tomllib

    from mjtvm.lift.states import lift_state
    from mjtvm.lift.trajectory import scripted_lift

    doc = tomllib.loads(shipped_grasps()["gripper3-box"].read_text(encoding="utf-8"))
    doc["model"] = str(shipped_grasps()["gripper3-box"].with_name("gripper3.xml"))
    box = scripted_lift(load_grasp(doc), num_states=5)
    doc["model"] = str(_box_as_two_mesh_pieces(tmp_path, -0.005))
    pieces = scripted_lift(load_grasp(doc), num_states=5)
    model = pieces.scenario.model
    assert int(model.geom_type[model.geom("upper").id]) == int(mujoco.mjtGeom.mjGEOM_MESH)
    np.testing.assert_allclose(pieces.s, box.s, atol=1e-12)
    np.testing.assert_allclose(pieces.qpos, box.qpos, atol=1e-7)
    np.testing.assert_allclose(pieces.points, box.points, atol=1e-7)
    # the L finger's piece: the upper one at the start, the lower one at the end
    data = mujoco.MjData(model)
    ob = model.body("object").id
    for i, piece in ((0, "upper"), (4, "lower")):
        data.qpos[:] = pieces.qpos[i]
        mujoco.mj_kinematics(model, data)
        k = pieces.roles.index("N")
        height = (data.xmat[ob].reshape(3, 3).T @ (pieces.points[i][k] - data.xpos[ob]))[2]
        assert (height > -0.005) == (piece == "upper"), (i, height)
        gap = mujoco.mj_geomDistance(
            model, data, model.geom(piece).id, geom_id(model, pieces.geoms[k]), 1.0, None
        )
        assert abs(gap) < 1e-7
    for i in range(1, 5):
        a, b = mjtvm.tvmmp(lift_state(pieces, i)), mjtvm.tvmmp(lift_state(box, i))
        np.testing.assert_allclose(
            np.asarray(a.alpha, dtype=float), np.asarray(b.alpha, dtype=float), rtol=1e-6, atol=1e-9
        )
