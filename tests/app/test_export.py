"""Export BVH's options and imported clips on the grid, in the model (no window); Blender re-imports the studio's
export standing (Blender's own importer in a subprocess, skipped with the reason where bpy is missing)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from blender import blender_import

from gsik.io.bvh import read_bvh
from gsik_studio.model import Document, transfer

DATA = Path(__file__).resolve().parents[1] / "data"
MOCAP = Path(__file__).resolve().parents[3] / "shared" / "mocap" / "mocap_bvhtools_test.bvh"


def _neck_above_ankles(path) -> float:
    """How far the neck stands above the lower ankle along Blender's z, imported with Blender's defaults."""
    got = blender_import(path, frames=[1.0])
    assert got["ok"], got.get("error")
    heads = np.array(got["heads"][1.0])
    z = {name: heads[k, 2] for k, name in enumerate(got["bones"])}
    return z["neck"] - min(z["left_ankle"], z["right_ankle"])


def test_the_studio_exports_y_up_centimetres_and_blender_imports_the_figure_standing(tmp_path):
    doc = Document()
    assert transfer.BvhExportOptions() == ("y", "cm")
    P, sk = doc.world_positions(), doc.skeleton
    standing = 100 * (P[sk.frame_of("neck"), 2] - P[sk.frame_of("left_ankle"), 2])  # [cm]
    default = tmp_path / "default.bvh"
    transfer.export_bvh(doc, default)
    assert _neck_above_ankles(default) == pytest.approx(standing, rel=0.02)  # standing, head up, in cm
    # gsik's own z-up axes, read with Blender's y-up default, lay the figure on its back: the options matter.
    z_up = tmp_path / "z_up.bvh"
    transfer.export_bvh(doc, z_up, transfer.BvhExportOptions(up="z", units="cm"))
    assert abs(_neck_above_ankles(z_up)) < 0.3 * standing
    metres = tmp_path / "metres.bvh"
    transfer.export_bvh(doc, metres, transfer.BvhExportOptions(up="y", units="m"))
    assert _neck_above_ankles(metres) == pytest.approx(standing / 100, rel=0.02)


@pytest.mark.parametrize("path", [DATA / "walk_zxy.bvh", MOCAP], ids=["walk_zxy", "bvhtools_18_joints"])
def test_an_imported_clip_of_another_skeleton_is_placed_on_the_grid_keeping_its_motion(path):
    if not path.exists():
        pytest.skip(f"{path} is absent (../shared holds the motion capture)")
    motion = transfer.read_clip(path).motion
    placed = transfer.placed_on_grid(motion)
    before, after = motion.positions(), placed.positions()
    first = after[0]
    np.testing.assert_allclose(first[0, :2], 0.0, atol=1e-9)  # the root joint over the origin
    assert first[:, 2].min() == pytest.approx(0.0, abs=1e-9)  # standing on the ground
    shift = after - before
    np.testing.assert_allclose(shift, np.broadcast_to(shift[0, 0], shift.shape), atol=1e-9)  # moved, not changed
    np.testing.assert_array_equal(placed.q, motion.q)


def test_export_writes_the_chosen_units(tmp_path):
    doc = Document()
    for units, scale in (("cm", 100.0), ("m", 1.0)):
        path = tmp_path / f"{units}.bvh"
        transfer.export_bvh(doc, path, transfer.BvhExportOptions(up="y", units=units))
        clip = read_bvh(path)
        offsets = np.array([j.offset for j in clip.joints])
        assert 0.3 * scale < np.abs(offsets).max() < 1.5 * scale  # a limb's length, in the file's unit
        assert os.path.getsize(path) > 0
