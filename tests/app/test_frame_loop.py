"""The frame loop idles once the pose is at rest, also at a best reach under the studio's default pins: no window."""

from __future__ import annotations

import numpy as np
import pytest

from gsik_studio.model import Document
from gsik_studio.model.frame_loop import FrameLoop

#: A held drag must come to rest within this many frames (about 13 s at 30 fps).
MAX_FRAMES = 400


def _frames_until_idle(loop: FrameLoop) -> int:
    for frame in range(1, MAX_FRAMES + 1):
        if not loop.solve_frame():
            return frame
    return -1


def _set_posture(doc: Document, posture: str) -> None:
    """``"natural"`` (the learned prior, the studio's default), ``"rest"`` (the rest pose) or ``"none"``."""
    c = doc.controls
    if posture != "natural":
        c.set_natural(False)
        c.set_posture_strength(1.0 if posture == "rest" else 0.0)


@pytest.mark.parametrize("posture", ["natural", "rest", "none"])
@pytest.mark.parametrize("pull", [(0.0, 3.0, 0.0), (2.0, 0.0, 1.0), (0.0, -0.5, 2.5)])
def test_a_hand_held_out_of_reach_next_to_a_free_head_comes_to_rest(posture, pull):
    # Feet and pelvis pinned, head and hands free (the studio's defaults): the hand pulled
    # out of reach shares its level with the head. The loop must stop asking for frames, and
    # the pins must stay on their targets, while the artist holds the drag.
    doc = Document()
    _set_posture(doc, posture)
    loop = FrameLoop(doc, readout_interval=3600.0)
    assert _frames_until_idle(loop) > 0, "the standing pose never came to rest"
    pins = {n: np.array(doc.targets[n].position) for n in ("left_foot", "pelvis")}
    hand = np.array(doc.targets["left_hand"].position)
    doc.move_target("left_hand", hand + pull)
    frames = _frames_until_idle(loop)
    assert frames > 0, f"still solving after {MAX_FRAMES} frames with the hand held at {pull}"
    q = doc.q.copy()
    for _ in range(20):  # held: a frame asked for anyway changes nothing
        doc.step()
    np.testing.assert_array_equal(doc.q, q)
    achieved = doc.solver.effector_poses()
    for name, position in pins.items():
        assert np.linalg.norm(achieved[name][:3, 3] - position) < 1e-4, f"{name} left its pin"
    # The hand is out of reach: the loop idled at a best reach, not at convergence.
    assert np.linalg.norm(achieved["left_hand"][:3, 3] - doc.targets["left_hand"].position) > 0.4
