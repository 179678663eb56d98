"""Foot contacts (issue 17, item 4): detected low and slow, relative to body height and fps; pinned spans hold."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from gsik.anim.contacts import (ContactSettings, detect_contacts, pin_targets, planted_speed, point_speeds,
                                smoothed)


def _steps(fps: float, seconds: float = 3.0, drift: float = 0.02) -> np.ndarray:
    """(n, 1, 3) a foot that stands 0.5 s (drifting ``drift`` m/s forward), swings 0.5 s 0.6 m ahead, repeated."""
    t = np.arange(int(seconds * fps)) / fps
    phase = np.mod(t, 1.0)
    step = np.floor(t)
    swing = np.clip((phase - 0.5) / 0.5, 0.0, 1.0)
    x = 0.6 * (step + 0.5 - 0.5 * np.cos(np.pi * swing)) + drift * np.minimum(phase, 0.5)
    z = 0.08 + 0.12 * np.sin(np.pi * swing)
    return np.stack([x, np.zeros_like(x), z], axis=-1)[:, None]


def test_a_stance_is_one_span_per_step_at_30_and_120_fps_alike():
    spans = {}
    for fps in (30.0, 120.0):
        c = detect_contacts(_steps(fps), ("left_ankle",), fps, 1.75)
        spans[fps] = [(a / fps, b / fps) for _, a, b in c.spans]
        assert len(c.spans) == 3  # three stances, each ended by a swing
        for a, b in spans[fps]:
            assert np.fmod(a, 1.0) < 0.05 and 0.4 < b - a <= 0.55  # from the step's start, about half a second
    np.testing.assert_allclose(np.array(spans[30.0]), np.array(spans[120.0]), atol=0.05)


def test_a_slow_foot_high_above_its_lowest_level_is_not_planted():
    p = _steps(30.0)
    p[:45, 0, 2] += 0.3  # the first stance on a box 30 cm high (as high as the swing): not on the floor
    c = detect_contacts(p, ("left_ankle",), 30.0, 1.75)
    assert not c.planted[:45].any() and c.planted[45:].any()


def test_thresholds_scale_with_body_height():
    p = _steps(30.0, drift=0.06)  # 6 cm/s: slow for a 1.75 m body (limit 8.75 cm/s), fast for a 0.5 m one
    assert detect_contacts(p, ("foot",), 30.0, 1.75).planted.any()
    assert not detect_contacts(p, ("foot",), 30.0, 0.5).planted.any()


def test_pinned_spans_hold_one_place_and_ease_in_and_out():
    fps = 30.0
    p = _steps(fps)
    c = detect_contacts(p, ("left_ankle",), fps, 1.75)
    pinned = pin_targets(p, c)
    for _, a, b in c.spans:
        np.testing.assert_allclose(pinned[a:b, 0], np.broadcast_to(p[a:b, 0].mean(axis=0), (b - a, 3)))
    assert planted_speed(pinned, c.planted, fps) == 0.0
    assert planted_speed(p, c.planted, fps) > 0.015  # the drift before pinning
    free = ~c.planted[:, 0]
    far = free & (np.convolve(c.planted[:, 0], np.ones(2 * 3 + 1), "same") == 0)  # beyond the 0.1 s blends
    np.testing.assert_array_equal(pinned[far], p[far])
    jump = np.linalg.norm(np.diff(pinned[:, 0], axis=0), axis=-1).max()
    assert jump <= np.linalg.norm(np.diff(p[:, 0], axis=0), axis=-1).max() * 1.5  # eased: no pop


@settings(max_examples=30, deadline=None)
@given(st.floats(0.1, 2.0), st.integers(0, 2**31 - 1))
def test_pinning_never_moves_a_point_farther_than_its_span_reaches(height, seed):
    rng = np.random.default_rng(seed)
    p = np.cumsum(rng.normal(scale=0.01, size=(90, 2, 3)), axis=0)
    c = detect_contacts(p, ("a", "b"), 30.0, height, settings=ContactSettings(speed_fraction=0.5))
    pinned = pin_targets(p, c)
    for k, a, b in c.spans:
        reach = np.linalg.norm(p[a:b, k] - p[a:b, k].mean(axis=0), axis=-1).max()
        assert np.linalg.norm(pinned[a:b, k] - p[a:b, k], axis=-1).max() <= reach + 1e-12
    assert point_speeds(p, 30.0).shape == (90, 2)



@settings(max_examples=30, deadline=None)
@given(st.floats(0.5, 2.0), st.integers(0, 2**31 - 1))
def test_a_contact_never_holds_a_point_far_from_where_the_clip_has_it(height, seed):
    """Slowly wandering feet: every contact span's smoothed path stays within the release distance of its start,
    so the pin (the span's mean) is within twice that of the smoothed path."""
    rng = np.random.default_rng(seed)
    p = np.cumsum(rng.normal(scale=0.004, size=(120, 2, 3)), axis=0)
    settings_ = ContactSettings(speed_fraction=0.5)
    c = detect_contacts(p, ("a", "b"), 30.0, height, settings=settings_)
    radius = settings_.release_fraction * height
    path = smoothed(p, 3)  # the blend time (0.1 s) at 30 fps
    for k, a, b in c.spans:
        assert np.linalg.norm(path[a:b, k] - path[a, k], axis=-1).max() <= radius
        pin = pin_targets(p, c)[a:b, k]
        assert np.linalg.norm(pin - path[a:b, k], axis=-1).max() <= 2 * radius + 1e-12


def test_a_foot_that_creeps_through_a_stance_is_released_and_planted_anew_each_time_it_leaves_its_spot():
    fps = 30.0
    p = np.zeros((60, 1, 3))
    p[:, 0, 0] = np.linspace(0.0, 0.06, 60)  # 6 cm over 2 s (3 cm/s): low and slow throughout
    c = detect_contacts(p, ("toe",), fps, 1.75)
    radius = ContactSettings().release_fraction * 1.75
    assert len(c.spans) >= 2 and not c.planted.all()  # released where it left its spot: free, then planted anew
    pinned = pin_targets(p, c)
    assert planted_speed(pinned, c.planted, fps) == 0.0  # each contact holds still
    inside = c.planted[:, 0]
    assert np.abs(pinned[inside, 0, 0] - p[inside, 0, 0]).max() <= radius  # and near where the clip has it
