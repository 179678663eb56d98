"""Every hostile file class through every reader: one GsikError naming the file and the bound, at little cost."""

from __future__ import annotations

import os
import tracemalloc

import pytest

import gsik
from hostile import make_cases, readers, refusal
from gsik.io.files import read_bounded

pytestmark = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs and /dev/zero (POSIX)")

#: Most memory a refusal may take [bytes] (the files themselves are at most a few MB; bombs declare gigabytes).
REFUSAL_PEAK = 50 * 2**20


@pytest.fixture(scope="module")
def cases(tmp_path_factory):
    return make_cases(tmp_path_factory.mktemp("hostile"))


def test_the_cases_cover_every_reader_and_every_class(cases):
    assert {c.reader for c in cases} == set(readers())
    names = " ".join(c.name for c in cases)
    for kind in ("fifo", "zero", "urandom", "-byte", "declared_10GB", "inflates", "members", "shape_1e12",
                 "star", "deep", "frames_999999999", "links", "nested", "banana"):
        assert kind in names, kind


def test_each_hostile_file_is_refused_with_one_gsik_error_naming_the_file_and_the_bound(cases):
    for case in cases:
        exc = refusal(case.reader, case.path)
        assert isinstance(exc, gsik.GsikError), (case.name, repr(exc))
        message = str(exc)
        assert case.expect in message, (case.name, message)
        shown = case.path if os.path.basename(case.path) else case.path.rstrip("/")
        assert os.path.basename(shown) in message, (case.name, message)
        assert "\n" not in message and len(message) < 600, (case.name, message)


def test_refusing_each_hostile_file_takes_little_memory(cases):
    # one of each reader and class is enough: the bombs and the largest honest-looking files
    heavy = [c for c in cases if c.name.split(" ")[0] in ("declared_10GB.npz", "inflates_200MB.npz", "300_members.npz",
                                                          "shape_1e12.npz", "star.bvh", "deep.bvh", "nested.urdf",
                                                          "links.urdf", "frames_999999999.bvh", "values.bvh")
             or c.name.startswith(("zero as", "urandom as")) or "-byte" in c.name]
    assert len(heavy) >= 20
    for case in heavy:
        tracemalloc.start()
        try:
            exc = refusal(case.reader, case.path)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        assert isinstance(exc, gsik.GsikError), (case.name, repr(exc))
        assert peak < REFUSAL_PEAK, (case.name, peak)


def test_the_bounded_opener_reads_at_most_the_limit_and_only_regular_files(tmp_path):
    path = tmp_path / "ten.txt"
    path.write_bytes(b"0123456789")
    assert read_bounded(path, "test file", 10) == b"0123456789"
    with pytest.raises(gsik.GsikFileError, match=r"ten.txt': the file is 10 bytes; the limit is 9 bytes"):
        read_bounded(path, "test file", 9)
    with pytest.raises(gsik.GsikFileError, match=r"cannot read test file .*: not a regular file \(a folder\)"):
        read_bounded(tmp_path, "test file")
    with pytest.raises(gsik.GsikFileError, match="No such file"):
        read_bounded(tmp_path / "missing", "test file")


def test_mangled_prior_archives_are_read_or_refused_with_a_gsik_error(tmp_path):
    import random

    from hostile import _zip, prior_members
    valid = _zip(prior_members())
    rng = random.Random(2024)
    path = tmp_path / "p.npz"
    outcomes = {"read": 0, "refused": 0}
    for _ in range(300):
        data = bytearray(valid)
        for _ in range(rng.randint(1, 8)):
            data[rng.randrange(len(data))] = rng.randrange(256)
        if rng.random() < 0.2:
            data = data[: rng.randrange(len(data))]
        path.write_bytes(bytes(data))
        exc = refusal("prior", str(path))
        assert exc is None or isinstance(exc, gsik.GsikError), repr(exc)
        outcomes["read" if exc is None else "refused"] += 1
    assert outcomes["refused"] > 100  # the mutations reach the checks
