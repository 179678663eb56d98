"""Humanoid recognition by the tree's shape where names fail (issue 17, item 1): numbered joints, another
language, y-up and z-up, T- and A-pose; lower confidence than names; a mapping over it; clear refusals."""

from __future__ import annotations

import numpy as np
import pytest
from humanoid_rigs import CONVENTIONS, NUMBERED, build

import gsik
from gsik.humanoid import REQUIRED_BONES, Rig, recognise, rig_from_clip

#: Conventions without in-chain split bones (Rigify's .001, Daz's Bend/Twist, MakeHuman's 01/02): their shape alone
#: reads right (the split ones need their names: the longest two bones of a split arm are not the arm's).
UNSPLIT = [c for c in CONVENTIONS if c.name not in ("rigify", "daz", "makehuman")]
JAPANESE = ["腰", "背骨", "胸", "首", "頭", "頭先", "左肩", "左腕", "左ひじ", "左手首", "左指", "右肩", "右腕",
            "右ひじ", "右手首", "右指", "左足", "左ひざ", "左足首", "左つま先", "右足", "右ひざ", "右足首", "右つま先"]


def _renamed(rig: Rig, names) -> tuple[Rig, dict[str, str]]:
    names = tuple(names)
    return Rig(names, rig.parents, rig.rest_positions), dict(zip(rig.names, names))


@pytest.mark.parametrize("up", ["y", "z"])
@pytest.mark.parametrize("a_pose", [False, True], ids=["T", "A"])
def test_a_rig_of_numbers_is_read_from_its_shape(a_pose, up):
    t = build(NUMBERED, a_pose, up)
    r = recognise(t.rig)
    assert {b: r.bones.get(b) for b in t.expect} == t.expect
    assert all(r.method[b] == "structure" for b in r.bones)
    assert all(0.3 <= r.confidence[b] <= 0.7 for b in r.bones)  # below any name's
    np.testing.assert_allclose(r.up, [0, 1, 0] if up == "y" else [0, 0, 1], atol=1e-9)


@pytest.mark.parametrize("up", ["y", "z"])
@pytest.mark.parametrize("a_pose", [False, True], ids=["T", "A"])
@pytest.mark.parametrize("conv", UNSPLIT, ids=[c.name for c in UNSPLIT])
def test_every_unsplit_convention_reads_the_same_with_its_names_replaced_by_numbers(conv, a_pose, up):
    t = build(conv, a_pose, up)
    rig, renamed = _renamed(t.rig, (f"joint{k}" for k in range(t.rig.n_joints)))
    r = recognise(rig)
    assert {b: r.bones.get(b) for b in t.expect} == {b: renamed[j] for b, j in t.expect.items()}


def test_a_rig_named_in_another_language_is_read_from_its_shape():
    t = build(NUMBERED, a_pose=True, up="z")
    order = ["0", "1", "2", "3", "4", "5"] + [f"{s}{k}" for s in "12" for k in range(5)] + [
        f"{s}{k}" for s in "12" for k in range(5, 9)]
    rig, renamed = _renamed(t.rig, (JAPANESE[order.index(n)] for n in t.rig.names))
    r = recognise(rig)
    assert r.bones["leftHand"] == "左手首" and r.bones["rightFoot"] == "右足首" and r.bones["head"] == "頭"
    assert all(r.bones[b] == renamed[t.expect[b]] for b in REQUIRED_BONES)


def test_names_and_shape_together_and_a_mapping_over_both():
    t = build(NUMBERED)
    names = [n if n not in ("15", "16", "17") else {"15": "LeftThigh", "16": "LeftShin", "17": "LeftFoot"}[n]
             for n in t.rig.names]
    rig, _ = _renamed(t.rig, names)
    r = recognise(rig, {"head": "5"})
    assert r.method["leftUpperLeg"] == "name" and r.bones["leftUpperLeg"] == "LeftThigh"
    assert r.method["rightUpperLeg"] == "structure" and r.bones["rightUpperLeg"] == "25"
    assert r.method["head"] == "map" and r.bones["head"] == "5"
    assert r.confidence["leftUpperLeg"] > r.confidence["rightUpperLeg"]


def test_a_one_armed_rig_is_refused_naming_what_is_missing():
    t = build(NUMBERED)
    keep = [j for j, n in enumerate(t.rig.names) if not n.startswith("2") or len(n) != 2 or int(n[1]) >= 5]
    index = {j: k for k, j in enumerate(keep)}
    rig = Rig(tuple(t.rig.names[j] for j in keep), tuple(index.get(t.rig.parents[j], -1) for j in keep),
              t.rig.rest_positions[keep])
    with pytest.raises(gsik.HumanoidError, match="no joint found for .*'leftUpperArm'.*joints: '0'"):
        recognise(rig)


def test_a_clip_rig_of_numbers_reads_like_its_named_twin():
    t = build(CONVENTIONS[0], a_pose=True)
    clip_rig = rig_from_clip(t.clip)
    rig, renamed = _renamed(clip_rig, (str(k) for k in range(clip_rig.n_joints)))
    named, numbered = recognise(clip_rig), recognise(rig)
    assert {b: renamed[j] for b, j in named.bones.items()} == dict(numbered.bones)
