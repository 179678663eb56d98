"""``gsik humanoid FILE`` (issue 17): the table of bones for a BVH of every convention and of numbers, a skeleton,
a mapping file over it, a refusal with exit code 2."""

from __future__ import annotations

import io
import json

import pytest
from humanoid_rigs import CONVENTIONS, NUMBERED, build, bvh_name

from gsik.cli import main
from gsik.io.bvh import write_bvh


def _run(*argv) -> tuple[int, str]:
    out = io.StringIO()
    return main(list(argv), out=out), out.getvalue()


def _rows(text: str) -> dict[str, tuple[str, float, str]]:
    rows = {}
    for line in text.splitlines()[2:]:
        parts = line.split()
        if len(parts) == 4 and parts[2].replace(".", "").isdigit():
            rows[parts[0]] = (parts[1], float(parts[2]), parts[3])
    return rows


@pytest.mark.parametrize("conv", CONVENTIONS + [NUMBERED], ids=[c.name for c in CONVENTIONS + [NUMBERED]])
def test_gsik_humanoid_names_every_part_of_a_bvh_rig(conv, tmp_path):
    t = build(conv, a_pose=True, up="z")
    path = tmp_path / "rig.bvh"
    write_bvh(path, t.clip)
    code, text = _run("humanoid", str(path))
    assert code == 0, text
    rows = _rows(text)
    assert {b: rows[b][0] for b in t.expect} == {b: bvh_name(j) for b, j in t.expect.items()}
    method = "structure" if conv is NUMBERED else "name"
    assert all(rows[b][2] == method for b in t.expect)
    assert "ignored:" in text and "not found:" in text


def test_gsik_humanoid_reads_a_skeleton_and_prints_json_with_a_mapping_over_it(tmp_path):
    code, text = _run("humanoid", "biped", "--json")
    assert code == 0
    data = json.loads(text)
    assert data["bones"]["leftUpperArm"]["joint"] == "left_shoulder" and data["up"] == [0.0, 0.0, 1.0]
    mapping = tmp_path / "map.yaml"
    mapping.write_text("format: 1\nmap:\n  head: head\n  left_hand: left_elbow\n")  # canonical, or a biped frame
    code, text = _run("humanoid", "biped", "--map", str(mapping))
    rows = _rows(text)
    assert code == 0 and rows["head"] == ("head", 1.0, "map") and rows["leftHand"] == ("left_elbow", 1.0, "map")


def test_gsik_humanoid_refuses_a_rig_that_is_no_humanoid_with_exit_code_2(tmp_path, capsys):
    code, _ = _run("humanoid", str(tmp_path.parent / "nope.bvh"))
    assert code == 2
    path = tmp_path / "arm.bvh"
    t = build(NUMBERED)
    from gsik.io.bvh import BvhClip
    write_bvh(path, BvhClip(t.clip.joints[:1], t.clip.frame_time, t.clip.motion[:, :6]))
    code, _ = _run("humanoid", str(path))
    assert code == 2 and "no joint found for 'hips'" in capsys.readouterr().err
