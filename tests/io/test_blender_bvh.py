"""Blender's own BVH importer (bpy, in a subprocess) against gsik's BVH forward kinematics.

What Blender does with a BVH file is written down in docs/blender_bvh.md; these tests pin it on
small hand-written files so that the rules an exporter must follow are checked with Blender itself.
Skipped, with the reason, where bpy is not installed.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from blender import blender_import, blender_python

from gsik.io.bvh import BvhClip, BvhJoint, bvh_forward_kinematics, read_bvh, write_bvh

DATA = Path(__file__).resolve().parents[1] / "data"
CHAINS = ("blender_chain_zxy_cm.bvh", "blender_chain_zyx_m.bvh")
SHORT_KNEES = ("blender_knee_1dof.bvh", "blender_knee_2dof.bvh")

# Blender's default import axes (axis_forward='-Z', axis_up='Y'): file x -> x, y -> z, z -> -y.
BLENDER_FROM_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
# axis_forward='Y', axis_up='Z' is Blender's own convention: no change.
BLENDER_FROM_Z_UP = np.eye(3)


def _file_from_blender(points: np.ndarray, blender_from_file: np.ndarray, scale: float) -> np.ndarray:
    """(..., 3) Blender world points back to file axes and units."""
    return points @ blender_from_file / scale


def _expected(path: Path) -> tuple[list[str], np.ndarray, float]:
    """Joint names (End Sites excluded), their FK positions (n_frames, n_joints, 3), body size."""
    clip = read_bvh(path)
    _, world_p = bvh_forward_kinematics(clip)
    joints = [j for j, joint in enumerate(clip.joints) if not joint.is_end_site]
    size = float(np.ptp(world_p.reshape(-1, 3), axis=0).max())
    return [clip.joints[j].name for j in joints], world_p[:, joints], size


def _assert_blender_heads_on_fk(
    path: Path, bvh_frames: list[int], blender_from_file: np.ndarray = BLENDER_FROM_Y_UP,
    fk_path: Path | None = None, tolerance: float = 1e-4, **options: object,
) -> dict:
    """Import ``path`` in Blender; its bones must be the file's joints (End Sites excluded), its heads
    on the FK of ``fk_path`` (default ``path``) at BVH frames ``bvh_frames``, to ``tolerance`` of the body size."""
    names, fk, size = _expected(fk_path or path)
    scale = options.get("global_scale", 1.0)
    got = blender_import(path, frames=[1 + k for k in bvh_frames], **options)
    assert got["ok"], f"Blender refused {path.name}: {got.get('error')}"
    assert got["bones"] == names
    np.testing.assert_allclose(np.array(got["global_matrix"]), blender_from_file, atol=1e-12)
    for k in bvh_frames:
        heads = _file_from_blender(np.array(got["heads"][1.0 + k]), blender_from_file, scale)
        np.testing.assert_allclose(heads, fk[k], atol=tolerance * size, err_msg=f"{path.name}, BVH frame {k}")
    return got


@pytest.mark.parametrize("name", CHAINS)
@pytest.mark.parametrize(
    ("options", "blender_from_file"),
    [
        ({}, BLENDER_FROM_Y_UP),
        ({"axis_forward": "Y", "axis_up": "Z", "rotate_mode": "QUATERNION"}, BLENDER_FROM_Z_UP),
        ({"rotate_mode": "XYZ", "global_scale": 0.01}, BLENDER_FROM_Y_UP),
    ],
    ids=["defaults", "z-up-quaternion", "xyz-euler-scaled"],
)
def test_blender_bone_heads_match_gsik_forward_kinematics(name, options, blender_from_file):
    _assert_blender_heads_on_fk(DATA / name, [0, 1, 3, 4], blender_from_file, **options)


def test_blender_makes_one_bone_per_joint_and_end_sites_become_tails():
    path = DATA / "blender_chain_zxy_cm.bvh"
    clip = read_bvh(path)
    got = blender_import(path)
    assert got["ok"], got.get("error")
    assert got["bones"] == ["Hips", "UpperLeg", "Knee"]
    assert got["parents"] == [None, "Hips", "UpperLeg"]
    rest_heads = _file_from_blender(np.array(got["rest_heads"]), BLENDER_FROM_Y_UP, 1.0)
    rest_tails = _file_from_blender(np.array(got["rest_tails"]), BLENDER_FROM_Y_UP, 1.0)
    offsets = np.array([j.offset for j in clip.joints])
    # Rest heads are summed OFFSETs, the root's included; the root's position channels are not used.
    np.testing.assert_allclose(rest_heads, np.cumsum(offsets[:3], axis=0), atol=1e-4)
    # A joint's tail is its only child's head; the last joint's tail is its End Site.
    np.testing.assert_allclose(rest_tails[:2], rest_heads[1:], atol=1e-4)
    np.testing.assert_allclose(rest_tails[2], rest_heads[2] + offsets[3], atol=1e-4)
    assert got["rotation_modes"] == ["ZXY"] * 3  # NATIVE keeps the file's order
    assert got["frame_range"] == [1.0, float(clip.n_frames)]


@pytest.mark.parametrize(
    ("name", "error"),
    [("blender_knee_1dof.bvh", "KeyError: (0, None, None)"), ("blender_knee_2dof.bvh", "KeyError: (0, 1, None)")],
)
def test_blender_refuses_joints_with_fewer_than_three_rotation_channels(name, error):
    # gsik reads these files; Blender's importer only knows 0 or 3 rotation channels (issue 9).
    assert read_bvh(DATA / name).n_frames == 5
    got = blender_import(DATA / name, frames=[1])
    assert not got["ok"]
    assert got["error"] == error


def _three_rotation_channels(clip: BvhClip, order: str) -> BvhClip:
    """``clip`` with every 1- or 2-rotation-channel joint written with three, the missing ones zero.

    The missing axes go where ``order`` (e.g. ``"ZXY"``) puts them when the joint's own axes keep
    that relative order, else after the joint's own: either way the product of the rotations, and so
    every frame's pose, is unchanged (an identity factor anywhere in the product).
    """
    joints, columns = [], []
    for j, joint in enumerate(clip.joints):
        values = clip.motion[:, clip.channel_index(j)]
        axes = [c[0] for c in joint.channels if c.endswith("rotation")]
        if not 0 < len(axes) < 3:
            joints.append(joint)
            columns.append(values)
            continue
        assert len(axes) == len(joint.channels), "position channels on a short joint: not needed here"
        in_order = "".join(a for a in order if a in axes) == "".join(axes)
        new = list(order) if in_order else axes + [a for a in order if a not in axes]
        zero = np.zeros(clip.n_frames)
        columns.append(np.stack([values[:, axes.index(a)] if a in axes else zero for a in new], axis=1))
        joints.append(BvhJoint(joint.name, joint.parent, joint.offset, tuple(a + "rotation" for a in new)))
    return BvhClip(tuple(joints), clip.frame_time, np.concatenate(columns, axis=1))


@pytest.mark.parametrize("name", SHORT_KNEES)
@pytest.mark.parametrize("order", ["ZXY", "YZX"])
def test_three_rotation_channels_with_zeros_make_short_joints_import_in_blender(name, order, tmp_path):
    # The export fix of issue 9: same motion, 3 rotation channels on every rotating joint.
    path = tmp_path / name
    write_bvh(path, _three_rotation_channels(read_bvh(DATA / name), order))
    _assert_blender_heads_on_fk(path, [0, 2, 4], fk_path=DATA / name)


def test_blender_keeps_only_the_last_of_several_end_sites(tmp_path):
    # gsik reads each End Site as a joint (Knee_end, Knee_end2); Blender makes no bone for any and
    # takes the last one as the joint's tail, so an End Site before it leaves no trace.
    text = (DATA / "blender_chain_zyx_m.bvh").read_text()
    first_site = "\t\t\tEnd Site\n\t\t\t{\n\t\t\t\tOFFSET 0.0000 -0.4000 0.0500\n\t\t\t}\n"
    assert first_site in text
    extra = first_site.replace("-0.4000 0.0500", "0.1000 0.3000")
    path = tmp_path / "two_end_sites.bvh"
    path.write_text(text.replace(first_site, first_site + extra))
    assert read_bvh(path).names == ("Hips", "UpperLeg", "Knee", "Knee_end", "Knee_end2")
    got = blender_import(path)
    assert got["ok"], got.get("error")
    assert got["bones"] == ["Hips", "UpperLeg", "Knee"]
    heads = _file_from_blender(np.array(got["rest_heads"]), BLENDER_FROM_Y_UP, 1.0)
    tails = _file_from_blender(np.array(got["rest_tails"]), BLENDER_FROM_Y_UP, 1.0)
    np.testing.assert_allclose(tails[2] - heads[2], [0.0, 0.1, 0.3], atol=1e-6)


# ---------------------------------------------------------------------------
# gsik's own exports (issue 9): the command line's files, read by Blender
# ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def exports(tmp_path_factory) -> dict[str, Path]:
    """BVH files written by ``gsik walk``, ``gsik scenarios`` and ``gsik track`` (a few seconds)."""
    python, why = blender_python()
    if python is None:
        pytest.skip(why)
    out = tmp_path_factory.mktemp("exports")
    commands = {
        "walk": ["walk", "--steps", "1", "--fps", "20", "--up", "y", "--out", str(out / "walk.bvh"), "--no-progress"],
        "scenario": ["scenarios", "--only", "kneel", "--max-frames", "10", "--out", str(out), "--no-progress"],
        "track": ["track", str(DATA / "walk_zxy.bvh"), "--out", str(out / "track.bvh")],
        "track_knees": ["track", str(DATA / "walk_zxy.bvh"), "--effectors", "LeftForeArm_end,RightLeg_end,LeftLeg",
                        "--pole", "RightLeg", "--out", str(out / "track_knees.bvh")],
        "walk_end_sites": ["walk", "--steps", "1", "--fps", "20", "--up", "y", "--end-sites", "--no-progress",
                           "--out", str(out / "walk_end_sites.bvh")],
    }
    for args in commands.values():
        subprocess.run([sys.executable, "-m", "gsik", *args], check=True, capture_output=True, timeout=300)
    return {name: out / f"{name}.bvh" for name in commands} | {"scenario": out / "kneel.bvh"}


def test_gsik_walk_export_imports_in_blender_on_its_fk(exports):
    _assert_blender_heads_on_fk(exports["walk"], [0, 18, 36])


def test_gsik_scenario_export_imports_in_blender_on_its_fk(exports):
    # scenarios write z-up by default
    _assert_blender_heads_on_fk(exports["scenario"], [0, 5, 9], BLENDER_FROM_Z_UP, axis_forward="Y", axis_up="Z")


def test_gsik_track_export_imports_in_blender_on_its_fk(exports):
    _assert_blender_heads_on_fk(exports["track"], [0, 1, 3], BLENDER_FROM_Z_UP, axis_forward="Y", axis_up="Z")


def test_gsik_track_export_keeps_the_clips_bones_in_blender(exports):
    got = blender_import(exports["track"])
    assert got["ok"], got.get("error")
    assert got["bones"] == _expected(DATA / "walk_zxy.bvh")[0]


def test_gsik_track_with_joint_targets_keeps_the_clips_body_in_blender(exports):
    # Knees as targets, by default y up as the clip: Blender's default axes, heads on the input clip's FK.
    _assert_blender_heads_on_fk(exports["track_knees"], [0, 1, 2, 3], fk_path=DATA / "walk_zxy.bvh", tolerance=1e-3)


def test_gsik_walk_with_end_sites_imports_in_blender_without_site_bones(exports):
    got = _assert_blender_heads_on_fk(exports["walk_end_sites"], [0, 9, 18])
    assert "left_hand" not in got["bones"] and "left_elbow" in got["bones"]
