"""A Blender-made glTF character in the real window: its skinned body drawn and posed by dragging, glTF export."""

from __future__ import annotations

import json
from typing import NamedTuple

import numpy as np
import pytest
from blender.gltf_characters import Spec, blender_read
from gltf_validator import assert_valid
from test_window import _drag
from waiting import wait_for

from gsik.io.gltf import read_gltf
from gsik.io.gltf.binding import skin_binding
from gsik.skinning import skinned

pytestmark = pytest.mark.gui


def _frames(doc) -> np.ndarray:
    T = np.zeros((doc.skeleton.n_frames, 4, 4))
    T[:, :3, :3], T[:, :3, 3], T[:, 3, 3] = doc.world_rotations(), doc.world_positions(), 1.0
    return T


#: One case per naming; across them A and T rests, with and without extra bones (twist, fingers, a prop).
CASES = (Spec("mixamo", "T", True), Spec("unreal", "A", False), Spec("vrm", "A", True), Spec("rigify", "T", False))


def _projected(window, points: np.ndarray) -> np.ndarray:
    """Normalised view coordinates (k, 2) of world points (k, 3): inside the 3D view where both lie in [-1, 1]."""
    ren = window.plotter.renderer
    M = ren.GetActiveCamera().GetCompositeProjectionTransformMatrix(ren.GetTiledAspectRatio(), -1, 1)
    M = np.array([[M.GetElement(i, j) for j in range(4)] for i in range(4)])
    h = np.c_[points, np.ones(len(points))] @ M.T
    return h[:, :2] / h[:, 3:]


@pytest.fixture(params=CASES, ids=lambda spec: spec.stem)
def character_window(request, window, blender_character):
    from gsik_studio.model.characters import character_of
    from gsik_studio.skinned_body import SkinnedBody

    path = blender_character(request.param)
    assert window.files.import_skeleton_path(str(path), confirm=False) is True
    character = character_of(window.doc.skeleton)
    assert character is not None and isinstance(window.body.mannequin, SkinnedBody)
    return window, character


def test_the_characters_skinned_body_is_drawn_framed_and_follows_a_drag(qtbot, character_window, tmp_path):
    window, character = character_window
    doc, body = window.doc, window.body.mannequin
    mesh = body.meshes[0]
    assert body.visible and body.n_vertices == read_gltf(character.file.path).n_vertices > 1000
    points = mesh.polydata.points  # the PolyData's own array: updated in place, never replaced
    np.testing.assert_allclose(points, skinned(skin_binding(character), _frames(doc))[0], atol=1e-6)
    # framed on open: every vertex of the body, head top to soles and both hands, projects inside the view
    xy = _projected(window, np.vstack([m.polydata.points for m in body.meshes]))
    assert np.abs(xy).max() < 1.0, f"the body is cropped: view coordinates up to {np.abs(xy).max(axis=0)}"
    assert np.ptp(xy[:, 1]) > 0.8, "the body is framed too small"
    shot = tmp_path / f"{character.name}.png"
    assert window.grab_window().save(str(shot))  # kept in the test folder to look at (body whole, lit, framed)
    name = character.effectors["left_hand"]
    start = np.array(doc.targets[name].position)
    hand = doc.effector_poses()[name][:3, 3].copy()
    before = np.array(points)
    _drag(window, start, (-70, 60))
    moved = np.array(doc.targets[name].position)
    assert np.linalg.norm(moved - start) > 0.05, "the drag did not move the target"
    wait_for(qtbot, lambda: np.linalg.norm(doc.effector_poses()[name][:3, 3] - moved)
             < 0.5 * np.linalg.norm(hand - moved))
    wait_for(qtbot, lambda: np.abs(mesh.polydata.points - before).max() > 0.02)
    assert mesh.polydata.GetPoints().GetData() is body.meshes[0].polydata.GetPoints().GetData()
    np.testing.assert_allclose(mesh.polydata.points, skinned(skin_binding(character), _frames(doc))[0], atol=1e-6)
    # File → Export glTF writes the pose on the character, which the validator passes and Blender shows
    doc.history.set_clean()
    out = tmp_path / "posed.glb"
    assert window.files.export_gltf_path(str(out)) is True
    assert_valid(out)
    got = blender_read(out)
    P = doc.world_positions()[doc.skeleton.joint_frame]
    assert len(got["bones"]) == len(character.file.skins[character.skin].joints)
    for bone, head in zip(got["bones"], got["pose_heads"]):
        np.testing.assert_allclose(head, P[character.file_names.index(bone)], atol=2e-5, err_msg=bone)


def test_the_biped_opens_framed_whole_from_every_preset_view(window):
    """A z-up skeleton's mannequin (the biped: its head and soles reach past its joints) in view from every side."""
    from gsik_studio.camera import VIEWS

    for view in VIEWS:
        window.set_view(view)
        xy = _projected(window, np.vstack([m.polydata.points for m in window.body.mannequin.meshes]))
        assert np.abs(xy).max() < 1.0, (view, np.abs(xy).max(axis=0))


@pytest.mark.parametrize("height", [0.15, 1.8, 40.0])
def test_a_body_of_any_height_is_framed_whole_from_every_preset_view(window, height):
    """Framing fits any size: a standing body's box (a tenth as wide as tall, arms out to 0.9 of its height)."""
    from gsik_studio import camera

    box = camera.box_corners((-0.45 * height, 0.45 * height, -0.1 * height, 0.1 * height, 0.0, height))
    for view in camera.VIEWS:
        camera.set_view(window.plotter, view, box)
        xy = _projected(window, box)
        assert np.abs(xy).max() < 1.0 and np.abs(xy).max() > 0.5, (view, np.abs(xy).max(axis=0))


def test_an_empty_mesh_adds_nothing_to_the_framed_extent():
    """VTK gives an empty mesh the bounds +-1e299: framing them sent the camera out of the world."""
    import pyvista as pv

    from gsik_studio.camera import body_extent

    class Body(NamedTuple):
        meshes: tuple
        visible: bool = True

    Mesh = NamedTuple("Mesh", [("polydata", object)])
    one = Mesh(pv.PolyData(np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]])))
    got = body_extent(Body((Mesh(pv.PolyData()), one)))
    assert got.shape == (8, 3) and got.min() == 0.0 and got.max() == 3.0
    assert body_extent(Body((one,), visible=False)).shape == (0, 3)


def test_a_bad_character_changes_nothing(qtbot, window, boxes, tmp_path):
    doc = window.doc
    bad = tmp_path / "bad.gltf"
    bad.write_text(json.dumps({"asset": {"version": "2.0"}, "nodes": [{"children": [0]}]}), encoding="utf-8")
    assert window.files.import_skeleton_path(str(bad), confirm=False) is False
    assert window.doc is doc and "child twice" in str(boxes["critical"][-1])


def test_a_characters_knee_pole_dragged_with_the_mouse_swings_the_knee(qtbot, window, blender_character, tmp_path):
    from test_artist_gui import _click_widget, _press_drag_release, _settle

    from gsik_studio.model.characters import character_of
    from gsik_studio.model.pole_places import limb_of, swing_angle

    assert window.files.import_skeleton_path(str(blender_character(CASES[0])), confirm=False) is True
    doc, character = window.doc, character_of(window.doc.skeleton)
    window.set_view("front")
    pelvis = character.effectors["pelvis"]
    doc.move_target(pelvis, doc.targets[pelvis].position + (0.0, 0.0, -0.08))  # crouch: the knees bend
    _settle(qtbot, window)
    _click_widget(window.balance_panel.poles)
    knee = character.poles["left_knee"]  # the character's own joint, mixamorig:LeftLeg
    assert set(doc.controls.poles) == set(character.poles.values()) and knee in window.poles.widgets
    _settle(qtbot, window)
    assert window.grab_window().save(str(tmp_path / "poles.png"))  # looked at by hand: drawn as the biped's
    P0, pole = doc.world_positions(), doc.controls.poles[knee].position.copy()
    at = doc.effector_poses()[pelvis][:3, 3].copy()
    xy = window.rings.project(pole[None])[0]
    _press_drag_release(window, xy, xy + np.array([80.0, 0.0]))  # the character faces the front view
    assert doc.controls.poles[knee].position[0] < pole[0] - 0.05
    assert [c.text for c in doc.history.commands][-1] == f"Move pole {knee}"
    _settle(qtbot, window)
    P = doc.world_positions()
    assert abs(np.degrees(swing_angle(limb_of(doc.skeleton, knee), P0, P))) > 10.0
    assert np.linalg.norm(doc.effector_poses()[pelvis][:3, 3] - at) < 1e-3
    other = limb_of(doc.skeleton, character.poles["right_knee"])
    assert abs(swing_angle(other, P0, P)) < np.radians(1.0)


def _screen_point(window, world) -> tuple[int, int]:
    """The X screen pixel (x, y) of a world point in the window's 3D view."""
    from PySide6 import QtCore

    pl = window.plotter
    x, y = window.viewport.world_to_display(world)
    ratio = pl.devicePixelRatioF()
    p = pl.mapToGlobal(QtCore.QPoint(int(round(x / ratio)), int(round(pl.height() - y / ratio - 1))))
    return p.x(), p.y()


def test_each_character_is_posed_by_a_drag_of_the_x_pointer(qtbot, character_window):
    """The drag an artist makes: X pointer events (xdotool, a separate process) through the X server, Qt and VTK's
    sphere widget onto the character's left-hand target; the hand follows it and the skinned body with it."""
    from test_wheel_window import _x

    window, character = character_window
    doc, mesh = window.doc, window.body.mannequin.meshes[0]
    wait_for(qtbot, lambda: not doc.needs_solving)
    name = character.effectors["left_hand"]
    start = np.array(doc.targets[name].position)
    hand = doc.effector_poses()[name][:3, 3].copy()
    before = np.array(mesh.polydata.points)
    x, y = _screen_point(window, start)
    moves = []
    for k in range(1, 11):
        moves += ["mousemove", str(x - 7 * k), str(y - 6 * k), "sleep", "0.05"]
    window.activateWindow()
    _x(qtbot, "mousemove", str(x), str(y), "sleep", "0.3", "mousedown", "1", "sleep", "0.2", *moves, "mouseup", "1")
    wait_for(qtbot, lambda: np.linalg.norm(doc.targets[name].position - start) > 0.05)
    moved = np.array(doc.targets[name].position)
    assert doc.history.undo_text.startswith("Move"), doc.history.undo_text
    wait_for(qtbot, lambda: np.linalg.norm(doc.effector_poses()[name][:3, 3] - moved)
             < 0.5 * np.linalg.norm(hand - moved))
    wait_for(qtbot, lambda: np.abs(mesh.polydata.points - before).max() > 0.02)
    np.testing.assert_allclose(mesh.polydata.points, skinned(skin_binding(character), _frames(doc))[0], atol=1e-6)
