"""Size limits: skeletons beyond what the dense solver can take are refused when built, and loading below them is
linear (no per-item list scans)."""

from __future__ import annotations

import numpy as np
import pytest

import gsik
from gsik.skeleton import JointSpec, RotationSpec, SiteSpec
from gsik.skeleton_builder import MAX_DOFS, MAX_FRAMES, MAX_NAME_CHARS


def _chain(n_joints: int, rotations_each: int = 1) -> list[JointSpec]:
    rots = tuple(RotationSpec((1.0, 0.0, 0.0), -1.0, 1.0, 0.0, f"r{k}") for k in range(rotations_each))
    return [JointSpec(f"j{i}", None if i == 0 else f"j{i - 1}", (0.0, 0.0, 0.01), rots) for i in range(n_joints)]


def test_a_skeleton_at_the_dof_limit_is_built():
    skeleton = gsik.build_skeleton("big", _chain(MAX_DOFS // 2, 2), [SiteSpec("tip", f"j{MAX_DOFS // 2 - 1}",
                                                                              (0.0, 0.0, 0.01))], [], ["tip"])
    assert skeleton.n_dofs == MAX_DOFS


@pytest.mark.parametrize("joints, words", [
    (_chain(MAX_DOFS + 1), f"{MAX_DOFS + 1:,} degrees of freedom; gsik's dense solver takes at most {MAX_DOFS:,}"),
    (_chain(100_000), "100,000 degrees of freedom"),
    (_chain(MAX_FRAMES + 1, 0), f"{MAX_FRAMES + 1:,} frames"),
])
def test_a_skeleton_beyond_the_limits_is_refused_when_built(joints, words):
    with pytest.raises(gsik.SkeletonError, match=words):
        gsik.build_skeleton("huge", joints, source="huge.yaml")


def test_a_skeleton_file_of_100k_joints_is_refused_naming_it(tmp_path):
    path = tmp_path / "huge.yaml"
    path.write_text("format: 1\nname: huge\njoints:\n" + "".join(f"  - {{name: j{i}}}\n" for i in range(100_000)))
    with pytest.raises(gsik.SkeletonError, match=rf"^{path}: 100,000 frames"):
        gsik.load_skeleton(path)


def test_ancestry_is_every_frame_and_those_above_it(biped):
    reference = np.zeros((biped.n_frames, biped.n_frames), dtype=bool)
    for f in range(biped.n_frames):
        a = f
        while a >= 0:
            reference[a, f] = True
            a = int(biped.frame_parent[a])
    np.testing.assert_array_equal(biped.ancestry, reference)
    assert not biped.ancestry.flags.writeable


@pytest.mark.parametrize("name, words", [("n" * (MAX_NAME_CHARS + 1), f"the limit is {MAX_NAME_CHARS}"),
                                         ("bad\udc80", "lone surrogate"), ("", "non-empty string")])
def test_names_a_pose_file_could_not_hold_are_refused(name, words):
    with pytest.raises(gsik.SkeletonError, match=words):
        gsik.build_skeleton("s", [JointSpec("top", None, (0.0, 0.0, 0.0))], [SiteSpec(name, "top", (0.0, 0.0, 0.0))])


def test_a_dof_name_over_the_limit_is_refused():
    rot = RotationSpec((1.0, 0.0, 0.0), -1.0, 1.0, 0.0, "x" * MAX_NAME_CHARS)
    with pytest.raises(gsik.SkeletonError, match="degree of freedom name"):
        gsik.build_skeleton("s", [JointSpec("top", None, (0.0, 0.0, 0.0), (rot,))])
