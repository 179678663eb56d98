"""Tests for gsik.io.bvh: writing (format, round trips, atomic saves)."""

from __future__ import annotations

import os
import stat

import numpy as np
import pytest
from bvh_cases import BASE, DATA

from gsik.errors import BvhError, GsikFileError
from gsik.io.bvh import (
    BvhClip,
    format_bvh,
    parse_bvh,
    read_bvh,
    write_bvh,
)

# ---------------------------------------------------------------------------
# Writing
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["walk_zxy.bvh", "mixamo_zyx_crlf.bvh", "six_channel.bvh", "cm_scale.bvh"])
def test_round_trip_fixtures(name):
    clip = read_bvh(DATA / name)
    text = format_bvh(clip)
    again = parse_bvh(text)
    assert again == clip
    assert format_bvh(again) == text


def test_format_layout():
    text = format_bvh(parse_bvh(BASE), precision=2)
    assert text.splitlines()[:12] == [
        "HIERARCHY",
        "ROOT Hips",
        "{",
        "\tOFFSET 0.00 0.00 0.00",
        "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
        "\tJOINT Chest",
        "\t{",
        "\t\tOFFSET 0.00 1.00 0.00",
        "\t\tCHANNELS 3 Zrotation Xrotation Yrotation",
        "\t\tEnd Site",
        "\t\t{",
        "\t\t\tOFFSET 0.00 0.50 0.00",
    ]
    assert text.splitlines()[12:] == [
        "\t\t}",
        "\t}",
        "}",
        "MOTION",
        "Frames: 2",
        "Frame Time: 0.04",
        "0.00 1.00 0.00 10.00 20.00 30.00 1.00 2.00 3.00",
        "0.00 1.00 0.00 11.00 21.00 31.00 4.00 5.00 6.00",
    ]
    assert text.endswith("\n")


def test_round_trip_to_printed_precision():
    clip = parse_bvh(BASE)
    noisy = BvhClip(clip.joints, 1 / 30, clip.motion + np.pi / 1000)
    again = parse_bvh(format_bvh(noisy, precision=3))
    np.testing.assert_allclose(again.motion, noisy.motion, atol=0.5e-3 + 1e-12)
    assert again.frame_time == 1 / 30  # the frame time is written exactly


def test_format_rejects_bad_precision():
    with pytest.raises(BvhError, match="precision"):
        format_bvh(parse_bvh(BASE), precision=-1)


def test_write_and_read_back(tmp_path):
    clip = read_bvh(DATA / "walk_zxy.bvh")
    path = tmp_path / "out.bvh"
    write_bvh(path, clip)
    assert read_bvh(path) == clip
    assert os.listdir(tmp_path) == ["out.bvh"]


@pytest.fixture
def old_file(tmp_path):
    path = tmp_path / "take.bvh"
    path.write_bytes(b"old contents\r\n")
    return path


@pytest.mark.parametrize("failing", ["replace", "fsync"])
def test_write_failure_leaves_old_file(old_file, monkeypatch, failing):
    def boom(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, failing, boom)
    with pytest.raises(OSError) as info:
        write_bvh(old_file, parse_bvh(BASE))
    monkeypatch.undo()
    assert isinstance(info.value, GsikFileError) and info.value.errno == 28
    assert "No space left on device" in str(info.value)
    assert old_file.read_bytes() == b"old contents\r\n"
    assert os.listdir(old_file.parent) == [old_file.name]  # no temp file left behind


@pytest.mark.parametrize(
    "clip, precision",
    [(None, 6), ("not a clip", 6), ("base", -3), ("base", 1.5)],
)
def test_unformattable_write_leaves_old_file(old_file, clip, precision):
    clip = parse_bvh(BASE) if clip == "base" else clip
    with pytest.raises(BvhError):
        write_bvh(old_file, clip, precision=precision)  # type: ignore[arg-type]
    assert old_file.read_bytes() == b"old contents\r\n"
    assert os.listdir(old_file.parent) == [old_file.name]


def test_write_keeps_permissions(old_file):
    old_file.chmod(0o640)
    write_bvh(old_file, parse_bvh(BASE))
    assert stat.S_IMODE(old_file.stat().st_mode) == 0o640
    assert read_bvh(old_file) == parse_bvh(BASE)


def test_write_into_missing_directory(tmp_path):
    with pytest.raises(GsikFileError):
        write_bvh(tmp_path / "missing" / "x.bvh", parse_bvh(BASE))
