"""The gsik command line: every subcommand's help, output, errors and exit codes."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gsik
from gsik.io.bvh import read_bvh
from gsik.cli import Progress, build_parser, main
from gsik.io.pose import read_pose, write_pose
from gsik.anim.scenarios import builtin_scenario, scenario_pose

DATA = Path(__file__).resolve().parents[1] / "data"
REPO = Path(gsik.__file__).resolve().parent.parent
COMMANDS = ("info", "solve", "walk", "scenarios", "track", "bench")


def run(*argv: str) -> tuple[int, str]:
    """Run ``gsik argv`` in-process; returns (exit code, stdout text)."""
    out = io.StringIO()
    code = main(list(argv), out=out)
    return code, out.getvalue()


@pytest.fixture(scope="module")
def biped():
    return gsik.load_skeleton("biped")


@pytest.fixture(scope="module")
def walk_bvh(tmp_path_factory):
    path = tmp_path_factory.mktemp("walk") / "walk.bvh"
    code, text = run("walk", "--steps", "2", "--fps", "30", "--out", str(path), "--no-progress")
    assert code == 0, text
    return path


# -- help and usage ------------------------------------------------------------------------------


def test_top_level_help_lists_every_command(capsys):
    assert main(["--help"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("usage: gsik")
    for command in COMMANDS:
        assert command in text


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_has_help(command, capsys):
    assert main([command, "--help"]) == 0
    text = capsys.readouterr().out
    assert text.startswith(f"usage: gsik {command}")
    assert "options:" in text


def test_version(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"gsik {gsik.__version__}"


def test_no_command_and_unknown_options_are_usage_errors(capsys):
    assert main([]) == 2
    assert "required: COMMAND" in capsys.readouterr().err
    assert main(["walk", "--stepz", "3"]) == 2
    assert "unrecognized arguments: --stepz" in capsys.readouterr().err
    assert main(["walk", "--steps", "0"]) == 2
    assert "--steps: expected a whole number >= 1" in capsys.readouterr().err


def test_console_script_entry_point_is_main():
    text = (REPO / "pyproject.toml").read_text()
    assert 'gsik = "gsik.cli:main"' in text
    assert build_parser().prog == "gsik"


# -- info ------------------------------------------------------------------------------------------


def test_info_prints_joints_dofs_limits_effectors_and_segments(biped):
    code, text = run("info", "biped")
    assert code == 0
    assert "30 degrees of freedom" in text and "14 segments" in text
    assert "IK root: right_foot" in text
    assert "effectors (6): head, pelvis, left_hand, right_hand, left_foot, right_foot" in text
    knee = next(line for line in text.splitlines() if line.strip().startswith("left_knee.x"))
    # Limits in degrees then radians: -2.79 rad is -159.9 degrees.
    assert knee.split() == ["left_knee.x", "-159.9", "0.0", "-2.9", "-2.7900", "0.0000", "-0.0500"]
    assert "left_thigh: left_hip -> left_knee" in text
    assert "pelvis: hips -> waist, left_hip, right_hip" in text


def test_info_json_is_the_skeleton_as_data(biped):
    code, text = run("info", "biped", "--json")
    assert code == 0
    info = json.loads(text)
    assert info["n_dofs"] == 30 and len(info["dofs"]) == 30
    assert info["root"] == "right_foot"
    assert info["effectors"] == list(biped.effector_sites)
    elbow = next(d for d in info["dofs"] if d["name"] == "left_elbow.x")
    assert elbow["joint"] == "left_elbow" and elbow["lower"] == 0.0 and elbow["upper"] == pytest.approx(2.62)
    assert elbow["upper_deg"] == pytest.approx(np.degrees(2.62))
    assert len(info["segments"]) == 14
    assert next(j for j in info["joints"] if j["name"] == "neck")["parent"] == "waist"


def test_info_reads_urdf_and_bvh_files():
    code, text = run("info", str(DATA / "humanoid.urdf"))
    assert code == 0 and "degrees of freedom" in text
    code, text = run("info", str(DATA / "walk_zxy.bvh"))
    assert code == 0 and "degrees of freedom" in text


def test_info_unknown_skeleton_is_an_error_listing_the_bundled_ones(capsys):
    code, text = run("info", "robot_dog")
    assert code == 2 and text == ""
    err = capsys.readouterr().err
    assert err.startswith("gsik: error: no bundled skeleton 'robot_dog'; bundled: 'biped'")


def test_info_missing_file_is_an_error_naming_it(tmp_path, capsys):
    missing = tmp_path / "nothing.yaml"
    assert run("info", str(missing))[0] == 2
    err = capsys.readouterr().err
    assert err.startswith("gsik: error:") and "nothing.yaml" in err


# -- solve -----------------------------------------------------------------------------------------


@pytest.fixture
def pose_file(tmp_path, biped):
    """The one-leg scenario's targets with the rest pose's angles."""
    path = tmp_path / "one_leg.yaml"
    write_pose(path, scenario_pose(builtin_scenario(biped, "one_leg")))
    return path


def test_solve_prints_status_and_errors_and_writes_the_solved_pose(pose_file, tmp_path, biped):
    out = tmp_path / "solved.yaml"
    code, text = run("solve", str(pose_file), "--out", str(out))
    assert code == 0
    assert "status: converged" in text
    for effector in ("head", "pelvis", "left_hand", "right_hand", "left_foot"):
        assert any(line.split()[:1] == [effector] for line in text.splitlines())
    assert f"wrote {out}" in text
    solved = read_pose(out, biped)
    assert solved.warnings == ()
    before = read_pose(pose_file, biped).pose
    assert solved.pose.targets == before.targets
    q = solved.pose.q(biped)
    assert np.abs(q - before.q(biped)).max() > 0.5  # the left knee came up
    T = biped.with_root("right_foot").effector_poses(q, solved.pose.world_from_root)
    for name, t in solved.pose.targets.items():
        assert np.linalg.norm(T[name][:3, 3] - np.array(t.position)) < 1e-3


def test_solve_with_the_paper_method_and_a_given_skeleton(pose_file):
    code, text = run("solve", str(pose_file), "--skeleton", "biped", "--paper", "--sweeps", "5")
    assert code == 0 and "status:" in text


def test_solve_missing_file(tmp_path, capsys):
    assert run("solve", str(tmp_path / "gone.yaml"))[0] == 2
    err = capsys.readouterr().err
    assert err.startswith("gsik: error: cannot read pose file") and "gone.yaml" in err


def test_solve_malformed_pose_names_the_line(pose_file, capsys):
    lines = pose_file.read_text().splitlines()
    k = next(i for i, line in enumerate(lines) if line.strip().startswith("waist.x:"))
    lines[k] = "  waist.x: not-a-number"
    pose_file.write_text("\n".join(lines) + "\n")
    assert run("solve", str(pose_file))[0] == 2
    err = capsys.readouterr().err
    assert err.startswith("gsik: error:") and f":{k + 1}" in err and "waist.x" in err


def test_solve_pose_without_skeleton_field_asks_for_one(tmp_path, capsys):
    path = tmp_path / "odd.yaml"
    path.write_text("just: text\n")
    assert run("solve", str(path))[0] == 2
    assert "give --skeleton" in capsys.readouterr().err


def test_solve_rejects_an_output_that_is_not_yaml(pose_file, tmp_path, capsys):
    assert run("solve", str(pose_file), "--out", str(tmp_path / "x.txt"))[0] == 2
    assert "pose files end in .yaml or .yml" in capsys.readouterr().err


# -- walk ------------------------------------------------------------------------------------------


def test_walk_prints_its_measures():
    code, text = run("walk", "--steps", "2", "--fps", "30", "--no-progress")
    assert code == 0
    assert text.startswith("walk: 2 steps of 0.4 m, 100 steps/min (0.6 s per step), 30 fps")
    assert "(2 root swaps)" in text
    assert "largest joint jump at a root swap" in text and "stance foot slide while root" in text
    assert "finite:                            yes" in text


def test_walk_writes_a_bvh_that_reads_back(walk_bvh):
    clip = read_bvh(walk_bvh)
    assert clip.names[0] == "hips"
    assert clip.frame_time == pytest.approx(1 / 30)
    assert clip.n_frames == int(4 * 0.6 * 30) + 1  # lead-in, 2 steps, settle


def test_walk_step_duration_sets_the_cadence():
    code, text = run("walk", "--steps", "1", "--step-duration", "0.5", "--fps", "20")
    assert code == 0 and "120 steps/min (0.5 s per step)" in text


def test_walk_bad_parameter_is_an_error_naming_it(capsys):
    assert run("walk", "--step-length", "5")[0] == 2
    assert "gsik: error: walk parameter step_length must be between 0.0 and 1.5 m" in capsys.readouterr().err
    assert run("walk", "--cadence", "nan")[0] == 2
    assert "expected a finite number" in capsys.readouterr().err


def test_walk_warns_when_the_gait_is_out_of_reach(capsys):
    code, _ = run("walk", "--steps", "2", "--step-length", "0.6", "--fps", "30")
    assert code == 0
    assert "gsik: warning: some targets stayed" in capsys.readouterr().err


def test_walk_into_a_missing_folder_is_an_error(tmp_path, capsys):
    assert run("walk", "--out", str(tmp_path / "no" / "walk.bvh"))[0] == 2
    assert "does not exist" in capsys.readouterr().err


def test_walk_needs_a_skeleton_with_feet(capsys):
    assert run("walk", "--skeleton", str(DATA / "two_link_arm.urdf"))[0] == 2
    assert "cannot walk" in capsys.readouterr().err


# -- scenarios -------------------------------------------------------------------------------------


def test_scenarios_print_the_table():
    code, text = run("scenarios", "--only", "reach_up", "impossible", "--random", "1", "--seed", "4")
    assert code == 0
    lines = text.splitlines()
    assert lines[0].split()[:4] == ["scenario", "root", "status", "settled"]
    assert "max dq after rad" in lines[0]
    rows = {line.split()[0]: line.split() for line in lines[2:]}
    assert set(rows) == {"reach_up", "impossible", "random-4"}
    assert rows["reach_up"][2:4] == ["converged", "yes"]
    assert rows["impossible"][2:4] == ["stalled", "yes"]
    assert rows["impossible"][-1] == "none" and rows["impossible"][-3] == "0.0e+00"  # no NaN, no oscillation


def test_scenarios_verbose_prints_each_effector():
    code, text = run("scenarios", "--only", "twist", "-v")
    assert code == 0 and "twist: converged" in text and "left_hand" in text


def test_scenarios_unknown_name_lists_the_valid_ones(capsys):
    assert run("scenarios", "--only", "backflip")[0] == 2
    assert "no scenario 'backflip'; scenarios: 'kneel', 'one_leg'" in capsys.readouterr().err


def test_scenarios_out_writes_a_pose_and_a_bvh_each(tmp_path, biped):
    folder = tmp_path / "out" / "scenarios"
    code, text = run("scenarios", "--only", "crouch", "--out", str(folder), "--up", "y")
    assert code == 0 and "wrote 2 files" in text
    pose = read_pose(folder / "crouch.yaml", biped).pose
    assert pose.root == "right_foot"
    clip = read_bvh(folder / "crouch.bvh")
    assert clip.n_frames > 10


# -- track -----------------------------------------------------------------------------------------


def test_track_reports_errors_and_time_per_frame(walk_bvh, tmp_path):
    out = tmp_path / "solved.bvh"
    code, text = run("track", str(walk_bvh), "--effectors", "head,pelvis", "--effectors", "left_hand", "right_hand",
                     "left_foot", "right_foot", "--out", str(out))
    assert code == 0
    assert "tracked head, pelvis, left_hand, right_hand, left_foot, right_foot with root hips" in text
    assert "position error:" in text and "time per frame:" in text
    max_error_mm = float(text.split("position error:")[1].split("max")[1].split("mm")[0])
    assert max_error_mm < 5.0
    assert read_bvh(out).n_frames == read_bvh(walk_bvh).n_frames


def test_track_unknown_effector_lists_the_valid_names(walk_bvh, capsys):
    assert run("track", str(walk_bvh), "--effectors", "nose")[0] == 2
    err = capsys.readouterr().err
    assert err.startswith("gsik: error:") and "'nose'" in err and "'left_hand'" in err


def test_track_missing_and_malformed_files(tmp_path, capsys):
    assert run("track", str(tmp_path / "none.bvh"))[0] == 2
    assert "none.bvh" in capsys.readouterr().err
    bad = tmp_path / "bad.bvh"
    bad.write_text("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 zero\n}\n")
    assert run("track", str(bad))[0] == 2
    err = capsys.readouterr().err
    assert err.startswith("gsik: error:") and "bad.bvh:4" in err


# -- bench, missing features, progress ---------------------------------------------------------------


def test_bench_quick_prints_the_tables():
    code, text = run("bench", "--quick", "--no-progress")
    assert code == 0
    assert "### Table 1" in text and "### Reach" in text


def test_progress_bar_draws_only_when_enabled_and_slow():
    stream = io.StringIO()
    with Progress("work", enabled=True, stream=stream, delay=0.0, width=10) as p:
        p(5, 10)
        p(10, 10)
    text = stream.getvalue()
    assert "\rwork [#####-----]  50% (5/10)" in text
    assert "\rwork [##########] 100% (10/10)" in text and text.endswith("\n")
    quiet = io.StringIO()
    with Progress("work", enabled=False, stream=quiet, delay=0.0) as p:
        p(1, 2)
    fast = io.StringIO()
    with Progress("work", enabled=True, stream=fast, delay=60.0) as p:
        p(1, 2)
    assert quiet.getvalue() == "" and fast.getvalue() == ""


# -- as a process ----------------------------------------------------------------------------------


def test_python_dash_m_gsik_runs_as_a_process(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    ok = subprocess.run([sys.executable, "-m", "gsik", "info", "biped"], cwd=tmp_path, env=env,
                        capture_output=True, text=True, timeout=120)
    assert ok.returncode == 0 and "skeleton biped" in ok.stdout and ok.stderr == ""
    bad = subprocess.run([sys.executable, "-m", "gsik", "solve", "missing.yaml"], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and bad.stdout == ""
    assert bad.stderr.startswith("gsik: error: cannot read pose file 'missing.yaml'")
