"""``mjtvm show --png``'s picture: every geom group drawn, contacts projected where they are,
nothing outside the canvas (MuJoCo's EGL renderer, as the CLI sets it)."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from mjtvm.grasp import load_grasp
from mjtvm.grasp.contacts.picture import BACKGROUND, DISTANCE_RADII, render_grasp
from mjtvm.grasp.contacts.touch import forward_touching, subtree
from mjtvm.jobs.figures import grasp_figure


@pytest.fixture(scope="module")
def allegro():  # type: ignore[no-untyped-def]
    return load_grasp("allegro-ik")


def _hand_geoms(grasp) -> np.ndarray:  # type: ignore[no-untyped-def]
    inside = subtree(grasp.model, grasp.model.body(grasp.object_body).id)
    return np.array([g for g in range(grasp.model.ngeom) if int(grasp.model.geom_bodyid[g]) not in inside])


def _drawn(grasp) -> int:  # type: ignore[no-untyped-def]
    """Pixels of the three views that are not background."""
    pic = render_grasp(grasp.model, grasp.data, grasp.object_body, grasp.contact_tolerance, mu=grasp.mu)
    return sum(int(np.any(p != np.array(BACKGROUND, np.uint8), axis=-1).sum()) for p in pic.panels)


def test_a_hand_in_group_3_is_drawn_and_a_removed_hand_is_not(allegro) -> None:  # type: ignore[no-untyped-def]
    m, hand = allegro.model, _hand_geoms(allegro)
    group, rgba = m.geom_group.copy(), m.geom_rgba.copy()
    try:
        as_shipped = _drawn(allegro)
        m.geom_group[hand] = 3  # the menagerie's collision group
        in_group_3 = _drawn(allegro)
        m.geom_rgba[hand, 3] = 0.0  # alpha 0: MuJoCo draws nothing
        removed = _drawn(allegro)
    finally:
        m.geom_group[:], m.geom_rgba[:] = group, rgba
    assert in_group_3 == as_shipped  # the group does not matter
    assert in_group_3 - removed > 0.05 * 3 * 480 * 480  # the hand's pixels: present, then absent


def test_contacts_project_where_a_pinhole_camera_puts_them(allegro) -> None:  # type: ignore[no-untyped-def]
    """Top view, the camera DISTANCE_RADII ball radii above the ball's centre: a contact at
    horizontal distance r from the centre and height h above it is r D / (D - h) metres from
    the image centre at the scale metres_per_pixel (pinhole; the view's 1 deg tilt aside)."""
    m, d = allegro.model, copy.copy(allegro.data)
    pic = render_grasp(m, d, allegro.object_body, allegro.contact_tolerance, mu=allegro.mu)
    assert pic.object_contacts == 4 and pic.self_contacts == 0
    ob = m.body(allegro.object_body).id
    forward_touching(m, d, ob, allegro.contact_tolerance)
    points = np.array([c.pos for c in d.contact[: d.ncon] if c.dist <= allegro.contact_tolerance])
    offset = points - d.xpos[ob]
    big_d = DISTANCE_RADII * float(m.geom_rbound[m.body(allegro.object_body).geomadr[0]])
    expected = np.sort(np.linalg.norm(offset[:, :2], axis=1) * big_d / (big_d - offset[:, 2]))
    top = pic.labels.index("top")
    drawn = np.sort(np.linalg.norm(pic.marks[top].points - 240.0, axis=1) * pic.metres_per_pixel[top])
    np.testing.assert_allclose(drawn, expected, rtol=0.03)
    # 12 cone edges per contact with a friction coefficient
    assert pic.marks[top].cone_segments.shape == (4 * 12, 2, 2)


def test_no_text_outside_the_canvas(allegro) -> None:  # type: ignore[no-untyped-def]
    pic = render_grasp(
        allegro.model, allegro.data, allegro.object_body, allegro.contact_tolerance, mu=allegro.mu
    )
    fig = grasp_figure(pic, "allegro-ik: a title as long as a grasp file's name may be, with units (mm)")
    fig.canvas.draw()
    tight = fig.get_tightbbox(fig.canvas.get_renderer())
    width, height = fig.get_size_inches()
    assert tight.x0 >= 0 and tight.y0 >= 0 and tight.x1 <= width and tight.y1 <= height
    labels = [ax.get_title() for ax in fig.axes]
    assert labels == list(pic.labels)
    assert any(t.get_text().endswith(" mm") for ax in fig.axes for t in ax.texts)  # the scale bars
