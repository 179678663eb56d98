"""Keys baked in chunks (KeyedBake): the frames of a one-go bake, Play that never solves the whole sequence at once,
and Export BVH stepped in chunks that writes only at the end (a cancelled export writes nothing)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import gsik
from gsik.io.bvh import read_bvh
from gsik.io.bvh_skeleton import write_motion_bvh
from gsik_studio.model import Document, transfer
from gsik_studio.model.bake import BAKE_AHEAD, KeyedBake, bake_keys
from gsik_studio.model.keys import interpolated_targets
from gsik_studio.model.timeline import BAKE_FRAMES_PER_TICK

REACH = np.array([0.0, 0.25, 0.3])  # the left hand's move between keys [m]


class Clock:
    """A fake clock the test moves by hand [s]."""

    def __init__(self):
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


def keyed_doc(frames) -> Document:
    """A document keyed at ``frames``: standing, then the left hand reached out and back in turn."""
    doc = Document()
    hand = np.array(doc.targets["left_hand"].position)
    for n, f in enumerate(frames):
        doc.move_target("left_hand", hand + REACH * (n % 2))
        for _ in range(200):
            doc.step()
            if not doc.needs_solving:
                break
        doc.timeline.add_key(f)
    return doc


@pytest.fixture(scope="module")
def three_keys():
    doc = keyed_doc([0, 20, 45])
    tl = doc.timeline
    one_go = bake_keys(doc.skeleton, doc.settings, tl.keys, 1 / 30, n_frames=60)
    return doc, one_go


def _new_bake(doc):
    return KeyedBake(doc.skeleton, doc.settings, doc.timeline.keys, 1 / 30, n_frames=60)


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.integers(1, 25), min_size=1, max_size=40))
def test_baking_in_chunks_of_any_size_gives_the_one_go_frames(three_keys, chunks):
    doc, one_go = three_keys
    bake = _new_bake(doc)
    for c in chunks:
        before = bake.solved
        assert bake.step(c) == min(c, 60 - before) and bake.solved == min(60, before + c)
    bake.step(60)
    assert bake.done and bake.step(5) == 0
    m = bake.motion()
    assert m.roots == one_go.roots and m.n_frames == 60
    np.testing.assert_array_equal(m.q, one_go.q)
    np.testing.assert_array_equal(m.world_from_root, one_go.world_from_root)


def test_a_frame_asked_for_near_the_bake_is_baked_up_to_and_exact(three_keys):
    doc, one_go = three_keys
    bake = _new_bake(doc)
    for i in (30, 5, 59, 44):
        f = bake.frame(i)
        np.testing.assert_array_equal(f.q, one_go.q[i])
        np.testing.assert_array_equal(f.world_from_root, one_go.world_from_root[i])
    assert bake.solved == 60
    with pytest.raises(gsik.GsikError, match="baked up to"):
        _new_bake(doc).motion()
    with pytest.raises(gsik.GsikError, match="outside"):
        bake.frame(60)


def test_a_frame_far_ahead_is_previewed_without_baking_the_frames_before_it():
    doc = keyed_doc([0, 2000])
    keys = doc.timeline.keys
    bake = KeyedBake(doc.skeleton, doc.settings, keys, 1 / 30, n_frames=2500)
    bake.step(10)
    far = 1000
    assert far > bake.solved + BAKE_AHEAD
    f = bake.frame(far)
    assert bake.solved == 10  # nothing baked for the preview
    want = interpolated_targets(keys[0], keys[2000], 0.5)["left_hand"].position
    doc.show_motion_frame(*f)
    assert np.linalg.norm(doc.effector_poses()["left_hand"][:3, 3] - want) < 0.02
    held = bake.frame(2400)  # past the last key: its pose exactly
    np.testing.assert_array_equal(held.q, np.clip(keys[2000].q(doc.skeleton), doc.skeleton.lower,
                                                  doc.skeleton.upper))
    assert held.root == keys[2000].root and bake.solved == 10


def test_play_bakes_a_chunk_per_tick_and_shows_the_clocks_frame_however_far():
    doc = keyed_doc([0, 9_999])
    tl, clock = doc.timeline, Clock()
    tl.clock = clock
    assert tl.play() and tl.bake.solved == 1  # Play itself solves the frame it shows only
    for n in range(1, 4):
        clock.t += tl.frame_time
        assert tl.tick() and tl.frame == n and tl.bake.solved == 1 + n * BAKE_FRAMES_PER_TICK
    clock.t += 5_000 * tl.frame_time  # far past the bake: the frame is previewed
    assert tl.tick() and tl.frame == 5_003 and tl.bake.solved == 1 + 4 * BAKE_FRAMES_PER_TICK
    want = interpolated_targets(tl.keys[0], tl.keys[9_999], 5_003 / 9_999)["left_hand"].position
    assert np.linalg.norm(doc.effector_poses()["left_hand"][:3, 3] - want) < 0.02
    tl.scrub(9_000)  # scrubbing solves the frame scrubbed to, alone
    assert tl.frame == 9_000 and not tl.bake.done
    tl.pause()


def test_export_in_chunks_writes_only_at_the_end_the_one_go_frames(three_keys, tmp_path):
    doc, one_go = three_keys
    doc.timeline.set_length(60)
    path, reference = tmp_path / "keys.bvh", tmp_path / "one_go.bvh"
    job = transfer.BvhExport(doc, path)
    steps = 0
    while not job.step(7):
        steps += 1
        assert not path.exists() and job.baked <= job.n_frames == 60
    assert steps >= 60 // 7 and job.what == "keys"
    write_motion_bvh(reference, one_go, units="cm", up="y")
    assert path.read_bytes() == reference.read_bytes()
    assert read_bvh(path).n_frames == 60


def test_a_cancelled_export_writes_nothing_and_leaves_a_file_there_unchanged(tmp_path):
    doc = keyed_doc([0, 300])
    path = tmp_path / "keys.bvh"
    path.write_text("the user's file\n")
    job = transfer.BvhExport(doc, path)
    for _ in range(3):
        assert job.step(10) is False
    job.cancel()
    with pytest.raises(gsik.GsikError, match="cancelled"):
        job.step(10)
    assert path.read_text() == "the user's file\n" and not job.finished
    assert doc.timeline.bake.solved == 30  # what was baked stays for the next export
