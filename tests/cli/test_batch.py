"""Folders of clips (issue 17, item 5): a local pool or a Dask cluster, one table, failures reported, nothing
written outside --out, the same bytes either way."""

from __future__ import annotations

import io
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from gsik.cli import main
from gsik.cli.batch import SCHEDULER_ENV, local_workers
from gsik.errors import GsikFileError
from gsik.io.bvh import read_bvh
from gsik.io.out_folder import OutputFolder
from gsik.prior import read_prior

DATA = Path(__file__).resolve().parents[1] / "data"
WALK = DATA / "retarget" / "long_shin_walk.bvh"


def run(*argv: str) -> tuple[int, str]:
    out = io.StringIO()
    code = main(list(argv), out=out)
    return code, out.getvalue()


@pytest.fixture
def clips(tmp_path) -> Path:
    """A folder of two walks (the second one shorter) and one broken clip."""
    folder = tmp_path / "clips"
    folder.mkdir()
    shutil.copy(WALK, folder / "a_walk.bvh")
    text = WALK.read_text()
    head, frames = text.split("MOTION\n")
    lines = frames.splitlines()
    (folder / "c_walk.bvh").write_text(head + "MOTION\nFrames: 60\n" + "\n".join(lines[1:62]) + "\n")
    (folder / "b_broken.bvh").write_text("HIERARCHY\nROOT Hips\n")
    return folder


def test_a_broken_clip_is_reported_by_name_and_the_others_are_written(clips, tmp_path):
    out = tmp_path / "out"
    code, text = run("retarget", str(clips), "--out", str(out), "--workers", "2", "--no-progress")
    assert code == 4, text  # some clips failed
    lines = text.splitlines()
    assert lines[0].split()[:2] == ["clip", "frames"] and "slide before" in lines[0] and "seconds" in lines[0]
    assert [line.split()[0] for line in lines[2:5]] == ["a_walk.bvh", "b_broken.bvh", "c_walk.bvh"]
    assert "error:" in lines[3] and "b_broken.bvh" in lines[3]
    assert lines[2].split()[1] == "109" and lines[4].split()[1] == "60" and lines[2].rstrip().split()[-2] == "ok"
    assert "1 of 3 clips failed; wrote 2 files" in text
    assert sorted(os.listdir(out)) == ["a_walk.bvh", "c_walk.bvh"]  # no temporary file left
    assert read_bvh(out / "a_walk.bvh").n_frames == 109


def test_a_symlink_planted_in_out_is_not_written_through(clips, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    outside = tmp_path / "outside.txt"
    outside.write_text("keep me")
    (out / "a_walk.bvh").symlink_to(outside)
    code, text = run("retarget", str(clips), "--out", str(out), "--no-progress")
    assert code == 4
    row = next(line for line in text.splitlines() if line.startswith("a_walk.bvh"))
    assert "error:" in row and "symbolic link" in row
    assert outside.read_text() == "keep me" and (out / "a_walk.bvh").is_symlink()
    assert read_bvh(out / "c_walk.bvh").n_frames == 60


def test_output_names_cannot_leave_the_folder(tmp_path):
    folder = OutputFolder.create(tmp_path / "out")
    for name in ("../escape.bvh", "sub/x.bvh", "..", ".", "", "/etc/passwd", "a\x00b"):
        with pytest.raises(GsikFileError, match="would leave --out"):
            folder.write_text(name, "x")
    assert sorted(os.listdir(tmp_path)) == ["out"] and os.listdir(tmp_path / "out") == []
    assert folder.write_text("ok.bvh", "x").read_text() == "x"


def test_a_result_outside_its_tolerance_exits_3_unwritten_and_force_writes_it(tmp_path):
    mapping = tmp_path / "map.yaml"
    # A knee asked to follow the ankle and the ankle the knee: the shin folds back past the knee's range (a hand
    # asked to follow a foot is followed: the biped bends down to it, since the retarget re-solves trapped frames).
    mapping.write_text("format: 1\nmap:\n  left_knee: LeftFoot\n  left_ankle: LeftLeg\n")
    out = tmp_path / "biped.bvh"
    code, text = run("retarget", str(WALK), "--map", str(mapping), "--out", str(out), "--no-progress")
    assert code == 3 and not out.exists()
    assert "left_knee" in text  # the report is printed before the refusal
    code, _ = run("retarget", str(WALK), "--map", str(mapping), "--out", str(out), "--no-progress", "--force")
    assert code == 0 and read_bvh(out).n_frames == 109


def test_workers_are_clamped_to_clips_and_cores():
    cores = os.cpu_count() or 1
    assert local_workers(None, 1) == 1 and local_workers(64, 3) == min(3, cores)
    assert local_workers(None, 1000) == cores


def test_a_scheduler_that_is_not_an_address_is_bad_input(clips, monkeypatch):
    monkeypatch.setenv(SCHEDULER_ENV, "my-cluster")
    code, _ = run("retarget", str(clips), "--no-progress")
    assert code == 2
    code, _ = run("track", str(clips), "--no-progress", "--scheduler", "localhost")
    assert code == 2


def test_learn_prior_from_a_folder_writes_one_prior_inside_out(clips, tmp_path):
    out = tmp_path / "prior"
    code, text = run("learn-prior", str(clips), "--stride", "1", "--out", str(out), "--no-progress")
    assert code == 4 and "b_broken.bvh" in text  # the broken clip is reported; the prior is learned without it
    # Every frame of both walks, and their mirror images (the bundled recipe).
    assert os.listdir(out) == ["prior.npz"] and read_prior(out / "prior.npz").n_frames == 2 * (109 + 60)


def test_the_local_pool_and_a_dask_local_cluster_write_the_same_bytes(clips, tmp_path):
    distributed = pytest.importorskip("distributed", reason="Dask is not installed (pip install 'gsik[dask]')")
    broken = tmp_path / "broken"
    broken.mkdir()
    (clips / "b_broken.bvh").rename(broken / "b_broken.bvh")
    local, remote = tmp_path / "local", tmp_path / "dask"
    assert run("retarget", str(clips), "--out", str(local), "--no-progress")[0] == 0
    assert run("learn-prior", str(clips), "--out", str(local), "--no-progress")[0] == 0
    assert run("track", str(clips), "--out", str(local / "tracked"), "--no-progress")[0] == 0
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) \
            as cluster:
        code, text = run("retarget", str(clips), "--out", str(remote), "--no-progress", "--scheduler",
                         cluster.scheduler_address)
        assert code == 0, text
        assert run("learn-prior", str(clips), "--out", str(remote), "--no-progress", "--scheduler",
                   cluster.scheduler_address)[0] == 0
        assert run("track", str(clips), "--out", str(remote / "tracked"), "--no-progress", "--scheduler",
                   cluster.scheduler_address)[0] == 0
        assert "run_clip" in cluster.scheduler.task_prefixes  # the clips ran as the cluster's tasks
        code, text = run("retarget", str(broken), "--no-progress", "--scheduler", cluster.scheduler_address)
        assert code == 4 and "b_broken.bvh  error:" in text  # a failure on the cluster is a row too
    assert sorted(os.listdir(local)) == sorted(os.listdir(remote)) == ["a_walk.bvh", "c_walk.bvh", "prior.npz",
                                                                        "tracked"]
    for name in ("a_walk.bvh", "c_walk.bvh", "prior.npz", "tracked/a_walk.bvh", "tracked/c_walk.bvh"):
        assert (local / name).read_bytes() == (remote / name).read_bytes(), name
    assert np.isfinite(read_prior(remote / "prior.npz").mean).all()


def test_clips_in_subfolders_are_found_and_two_of_one_name_are_refused(tmp_path):
    folder = tmp_path / "clips"
    (folder / "performer_a").mkdir(parents=True)
    shutil.copy(WALK, folder / "performer_a" / "walk_a.bvh")
    shutil.copy(WALK, folder / "walk_b.bvh")
    out = tmp_path / "out"
    code, text = run("retarget", str(folder), "--out", str(out), "--workers", "1", "--no-progress")
    assert code == 0, text
    assert sorted(os.listdir(out)) == ["walk_a.bvh", "walk_b.bvh"]
    (folder / "performer_b").mkdir()
    shutil.copy(WALK, folder / "performer_b" / "walk_a.bvh")
    code, text = run("retarget", str(folder), "--out", str(tmp_path / "out2"), "--no-progress")
    assert code == 2 and not (tmp_path / "out2").exists()
