"""One error contract and safe writes: hostile arguments and rigs give one GsikError (the CLI one line, exit 2),
and every write is atomic, keeps what it does not change and reads back."""

from __future__ import annotations

import io
import os
import subprocess
import sys

import numpy as np
import pytest

import gsik
from fuzzing import pose_of
from gsik.anim.motion import Motion
from gsik.cli.parser import main
from gsik.io.pose import KeySequence, Pole, read_pose, write_pose
from gsik.io.pose.model import Clip
from gsik.prior import fit_prior, read_prior, write_prior
from gsik.solver import MAX_PRIORITY_LEVELS, MAX_TARGETS
from hostile import human_bvh


def _cli(argv: list[str], capsys) -> tuple[int, str, str]:
    out = io.StringIO()
    code = main(argv, out)
    return code, out.getvalue(), capsys.readouterr().err


# -- arguments ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, error, message", [
    (dict(weights=10**400), gsik.SolverError, "posture weights must be numbers"),
    (dict(weights=np.full((30, 30), 1e308)), gsik.SolverError, "at most 1e\\+12 in magnitude, got 1e\\+308"),
    (dict(q="x"), gsik.SkeletonError, "joint angles must be numbers, got 'x'"),
    (dict(q=[object()] * 30), gsik.SkeletonError, "joint angles must be numbers"),
])
def test_set_posture_refuses_what_numpy_cannot_hold_with_one_gsik_error(biped, kwargs, error, message):
    solver = gsik.Solver(biped)
    with pytest.raises(error, match=message):
        solver.set_posture(**kwargs)
    assert solver.posture is None or np.all(np.isfinite(solver.posture[1]))


def test_targets_on_more_priority_levels_than_the_limit_are_refused_at_the_entry(biped):
    solver = gsik.Solver(biped)
    poses = solver.effector_poses()
    names = [n for n in biped.target_names if n != solver.root][:MAX_PRIORITY_LEVELS + 1]
    assert len(names) == MAX_PRIORITY_LEVELS + 1
    here = {n: gsik.Target(np.zeros(3) + 0.1 * k, priority=k) for k, n in enumerate(names)}
    with pytest.raises(gsik.TargetError, match=f"targets on {MAX_PRIORITY_LEVELS + 1} priority levels; the limit "
                                               f"is {MAX_PRIORITY_LEVELS}"):
        solver.step(here)
    solver.set_targets({n: here[n] for n in names[:-1]})
    with pytest.raises(gsik.TargetError, match="priority levels"):
        solver.set_target(names[-1], here[names[-1]])
    assert len(solver.targets) == MAX_PRIORITY_LEVELS and poses  # unchanged by the refusal
    assert MAX_TARGETS >= 4 * len(biped.target_names)  # the bound is far above a real rig's


# -- degenerate rigs through the command line -------------------------------------------------------------------

@pytest.mark.parametrize("bvh, message", [
    (human_bvh(offset="0"), "legs (hip to knee to ankle) are 0 file units long"),
    (human_bvh(offset="1e300"), "legs (hip to knee to ankle) are inf file units long"),
    (human_bvh(frames=0), "cannot retarget a clip of no frames (Frames: 0)"),
    (human_bvh(root_position="0 1e308 0"), "at frame 1 a joint is farther than 1e+10 file units"),
])
@pytest.mark.parametrize("command", [["retarget"], ["learn-prior", "--out", "{dir}/p.npz"]])
def test_degenerate_rigs_give_one_line_naming_the_clip(tmp_path, capsys, bvh, message, command):
    clip = tmp_path / "rig.bvh"
    clip.write_text(bvh)
    code, _, err = _cli([c.format(dir=tmp_path) for c in command] + [str(clip)], capsys)
    if command[0] == "learn-prior" and "Frames: 0" in message:
        message = "0 frames; learning a prior needs at least 10"  # refused before the retarget
    assert code == 2 and err.count("\n") == 1 and str(clip) in err and message in err, err
    assert not (tmp_path / "p.npz").exists()


@pytest.mark.parametrize("args, message", [
    (["learn-prior", "--out", "p.npz", "--frames", "-5"], "argument --frames: must be a whole number >= 1"),
    (["learn-prior", "--out", "p.npz", "--components", "40"], "argument --components: must be a count from 1 to 32"),
    (["learn-prior", "--out", "p.npz", "--components", "15"], "--components 15: 20 frames fit at most 10"),
    (["scenarios", "--random", str(10**12)], "the count must be a whole number from 0 to 10,000"),
])
def test_hostile_arguments_are_refused_up_front(tmp_path, capsys, monkeypatch, args, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "rig.bvh").write_text(human_bvh())
    code, out, err = _cli(args + (["rig.bvh"] if args[0] == "learn-prior" else []), capsys)
    assert code == 2 and message in err and "biped frame" not in out, err  # before any retarget


def test_track_reports_a_rig_of_no_height_instead_of_dividing_by_it(tmp_path, capsys):
    clip = tmp_path / "flat.bvh"
    clip.write_text(human_bvh(offset="0"))
    code, out, err = _cli(["track", str(clip), "--no-progress"], capsys)
    assert code == 0 and "Traceback" not in err and " - " in out.split("every joint and site")[1], out + err


# -- writes -------------------------------------------------------------------------------------------------------

def test_a_prior_save_that_fails_leaves_the_old_prior_whole(tmp_path, biped):
    path = tmp_path / "p.npz"
    Q = np.random.default_rng(0).normal(0.0, 0.1, (40, biped.n_dofs))
    write_prior(fit_prior(Q, biped), path)
    before = path.read_bytes()
    code = ("import resource, signal, sys, numpy as np, gsik\n"
            "from gsik.prior import fit_prior, write_prior\n"
            "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
            "sk = gsik.load_skeleton('biped')\n"
            "prior = fit_prior(np.random.default_rng(1).normal(0, 0.2, (40, sk.n_dofs)), sk, source='x' * 5000)\n"
            "resource.setrlimit(resource.RLIMIT_FSIZE, (1024, 1024))\n"
            "try:\n    write_prior(prior, sys.argv[1])\nexcept gsik.GsikFileError as e:\n    print('refused', e)\n")
    run = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, timeout=300)
    assert run.stdout.startswith("refused") and "p.npz" in run.stdout, run.stdout + run.stderr
    assert path.read_bytes() == before and read_prior(path).n_frames == 40
    assert [p.name for p in tmp_path.iterdir()] == ["p.npz"]  # no temporary file left


def test_solve_in_place_keeps_every_block_it_does_not_change(tmp_path, capsys, biped):
    pose = pose_of(biped)
    motion = Motion(biped, biped.rest[None].repeat(3, 0), ("left_knee",) * 3,
                                     np.eye(4)[None].repeat(3, 0), 1 / 30)
    path = tmp_path / "doc.yaml"
    write_pose(path, pose, library=(("a", pose), ("b", pose)), keys=KeySequence(((0, pose), (5, pose)), 24.0, 9),
               poles={"left_knee": Pole((0.1, 0.3, 0.5), True)}, clip=Clip("walk", motion))
    code, _, err = _cli(["solve", str(path), "--out", str(path)], capsys)
    assert code == 0, err
    back = read_pose(path, biped)
    assert [n for n, _ in back.library] == ["a", "b"] and [f for f, _ in back.keys.keys] == [0, 5]
    assert back.keys.fps == 24.0 and set(back.poles) == {"left_knee"}
    assert back.clip.name == "walk" and back.clip.motion.roots == ("left_knee",) * 3  # a rotating joint's clip


def test_a_pose_write_that_would_not_read_back_is_refused_and_nothing_is_written(tmp_path, biped):
    pose = pose_of(biped)
    bad = Motion(biped, biped.rest[None], ("left_knee",), np.diag([1.01, 1.01, 1.01, 1.0])[None], 1 / 30)
    path = tmp_path / "doc.yaml"
    path.write_text("old\n")
    with pytest.raises(gsik.PoseError, match="gsik would not read this pose file back .*world_from_root"):
        write_pose(path, pose, clip=Clip("c", bad))
    assert path.read_text() == "old\n" and os.listdir(tmp_path) == ["doc.yaml"]
