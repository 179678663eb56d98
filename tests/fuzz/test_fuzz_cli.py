"""The command line on hostile input: exit code 2 and one line on stderr, never a traceback."""

from __future__ import annotations

import pytest

from fuzzing import HOSTILE
from gsik.cli import main

INFO_FILES = ["alias_bomb_skeleton.yaml", "self_alias.yaml", "deep_nesting.yaml", "deep_mapping.yaml",
              "huge_int_skeleton.yaml", "huge_float.yaml", "python_tag.yaml", "custom_tag.yaml", "merge_key.yaml",
              "two_documents.yaml", "nul_byte.yaml", "utf16_bom.yaml", "latin1_name.yaml", "huge_offset.bvh",
              "huge_motion.bvh", "bogus_encoding.urdf", "overflow_axis.urdf", "xml_bomb.urdf"]


def _one_line_refusal(argv, capsys) -> str:
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2, err[-500:]
    assert err.count("\n") == 1 and err.startswith("gsik: error: "), err[-500:]
    assert "Traceback" not in err and len(err) < 500
    return err


@pytest.mark.parametrize("name", INFO_FILES)
def test_info_on_a_hostile_file_is_one_line_and_exit_2(name, capsys):
    err = _one_line_refusal(["info", str(HOSTILE / name)], capsys)
    assert name in err


def test_a_nul_in_a_path_is_one_line_and_exit_2(capsys):
    _one_line_refusal(["info", "bad\x00name.yaml"], capsys)


def test_a_path_too_long_for_the_system_is_one_line_and_exit_2(capsys):
    _one_line_refusal(["info", "n" * 5000 + ".yaml"], capsys)


@pytest.mark.parametrize("name", ["alias_bomb_pose.yaml", "self_alias.yaml", "deep_nesting.yaml",
                                  "huge_int_pose.yaml", "nul_byte.yaml"])
def test_solve_on_a_hostile_pose_is_one_line_and_exit_2(name, capsys):
    err = _one_line_refusal(["solve", str(HOSTILE / name), "--skeleton", "biped"], capsys)
    assert name in err


def test_solve_names_a_yaml_syntax_error_not_a_missing_skeleton(tmp_path, capsys):
    path = tmp_path / "broken.yaml"
    path.write_text("format: 1\nskeleton: [biped\n")
    err = _one_line_refusal(["solve", str(path)], capsys)
    assert f"{path}:" in err and "not valid YAML" in err


def test_a_pose_names_its_skeleton_file_relative_to_itself(tmp_path, monkeypatch, capsys):
    import shutil

    import gsik
    from fuzzing import pose_of
    from gsik.io.pose import pose_to_yaml
    folder = tmp_path / "project"
    (folder / "rigs").mkdir(parents=True)
    shutil.copy(fuzzing_root() / "skeletons" / "biped.yaml", folder / "rigs" / "biped.yaml")
    text = pose_to_yaml(pose_of(gsik.load_skeleton("biped"))).replace("skeleton: biped", "skeleton: rigs/biped.yaml")
    (folder / "pose.yaml").write_text(text)
    monkeypatch.chdir(tmp_path)  # elsewhere: rigs/biped.yaml does not exist here
    assert main(["solve", str(folder / "pose.yaml")]) == 0, capsys.readouterr().err


def fuzzing_root():
    from fuzzing import ROOT
    return ROOT
