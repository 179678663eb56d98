"""Bad glTF files: one clear GsikError each, before any large allocation, and nothing written."""

from __future__ import annotations

import base64
import json
import struct
from pathlib import Path

import numpy as np
import pytest

import gsik
from gsik.anim.motion import Motion
from gsik.cli import main
from gsik.errors import GltfError, GsikError, HumanoidError
from gsik.io.gltf import character_from_skeleton, read_character, read_gltf, write_gltf
from gsik.io.gltf.load import MAX_BUFFER_BYTES

POSE = str(Path(__file__).resolve().parents[2] / "docs" / "studio_pose.yaml")


@pytest.fixture(scope="module")
def biped_gltf(tmp_path_factory) -> dict:
    """The biped with its mannequin written as a .gltf with an embedded buffer: its JSON, to spoil."""
    biped = gsik.load_skeleton("biped")
    path = tmp_path_factory.mktemp("good") / "biped.gltf"
    W = gsik.Solver(biped).world_from_root
    write_gltf(path, character_from_skeleton(biped), Motion(biped, biped.rest[None], (biped.root,), W[None], 0.1))
    return json.loads(path.read_text(encoding="utf-8"))


def _write(tmp_path, doc: dict, name: str = "bad.gltf"):
    path = tmp_path / name
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


def _buffer(doc: dict) -> bytes:
    return base64.b64decode(doc["buffers"][0]["uri"].split(",", 1)[1])


def _with_buffer(doc: dict, data: bytes) -> dict:
    out = json.loads(json.dumps(doc))
    out["buffers"][0] = {"byteLength": len(data),
                         "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}
    return out


def test_the_unspoilt_file_reads(biped_gltf, tmp_path):
    assert read_gltf(_write(tmp_path, biped_gltf)).n_vertices > 1000


def test_a_skeleton_that_is_no_humanoid_is_refused_by_recognition(tmp_path):
    chain = gsik.skeleton_from_dict({
        "name": "arm", "root": "base", "effectors": ["tip"],
        "joints": [{"name": "base", "offset": [0, 0, 0]},
                   {"name": "j1", "parent": "base", "offset": [0, 0, 0.3], "rotations": [{"axis": "x", "limits": [-1, 1]}]},
                   {"name": "j2", "parent": "j1", "offset": [0, 0, 0.3], "rotations": [{"axis": "x", "limits": [-1, 1]}]}],
        "sites": [{"name": "tip", "parent": "j2", "offset": [0, 0, 0.2]}]})
    path = tmp_path / "arm.glb"
    write_gltf(path, character_from_skeleton(chain), Motion(chain, chain.rest[None], ("base",), np.eye(4)[None], 0.1))
    with pytest.raises(HumanoidError, match="hips|required|missing"):
        read_character(path)


def test_a_file_without_a_skin_is_refused(biped_gltf, tmp_path):
    doc = json.loads(json.dumps(biped_gltf))
    del doc["skins"]
    for node in doc["nodes"]:
        node.pop("skin", None)
    with pytest.raises(GltfError, match="no skin"):
        read_character(_write(tmp_path, doc))


def test_weights_that_do_not_sum_to_one_are_refused(biped_gltf, tmp_path):
    doc = biped_gltf
    prim = doc["meshes"][0]["primitives"][0]
    accessor = doc["accessors"][prim["attributes"]["WEIGHTS_0"]]
    view = doc["bufferViews"][accessor["bufferView"]]
    data = bytearray(_buffer(doc))
    struct.pack_into("<f", data, view["byteOffset"] + 16 * 7, 0.5)  # vertex 7's first weight: 1 -> 0.5
    with pytest.raises(GltfError, match=r"do not sum to 1 \(vertex 7"):
        read_gltf(_write(tmp_path, _with_buffer(doc, bytes(data))))


def test_a_buffer_shorter_than_declared_is_refused(biped_gltf, tmp_path):
    doc = json.loads(json.dumps(biped_gltf))
    data = _buffer(doc)
    doc = _with_buffer(doc, data[: len(data) // 2])
    doc["buffers"][0]["byteLength"] = len(data)
    with pytest.raises(GltfError, match="declares .* bytes but holds"):
        read_gltf(_write(tmp_path, doc))


def test_an_accessor_past_its_buffer_view_is_refused(biped_gltf, tmp_path):
    doc = json.loads(json.dumps(biped_gltf))
    doc["accessors"][doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"]]["count"] = 10_000_000
    with pytest.raises(GltfError, match="elements need .* bytes of its bufferView"):
        read_gltf(_write(tmp_path, doc))


@pytest.mark.parametrize("uri", ["../outside.bin", "sub/../../outside.bin", "/etc/passwd", "file:///etc/passwd",
                                 "https://example.invalid/a.bin"])
def test_a_uri_outside_the_files_folder_is_refused(biped_gltf, tmp_path, uri):
    (tmp_path / "outside.bin").write_bytes(_buffer(biped_gltf))
    folder = tmp_path / "model"
    (folder / "sub").mkdir(parents=True)
    doc = json.loads(json.dumps(biped_gltf))
    doc["buffers"][0]["uri"] = uri
    with pytest.raises(GltfError, match="outside the glTF file's folder|not a relative file name"):
        read_gltf(_write(folder, doc))


def test_a_data_uri_bomb_is_refused_before_decoding(biped_gltf, tmp_path):
    doc = json.loads(json.dumps(biped_gltf))
    doc["buffers"][0]["byteLength"] = 16
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + "A" * 4_000_000
    with pytest.raises(GltfError, match="more than the 16 bytes it declares"):
        read_gltf(_write(tmp_path, doc))
    doc["buffers"][0]["byteLength"] = 2 * MAX_BUFFER_BYTES
    with pytest.raises(GltfError, match="gsik reads at most"):
        read_gltf(_write(tmp_path, doc))


def test_json_past_the_limit_is_refused_before_parsing(tmp_path, monkeypatch):
    monkeypatch.setattr("gsik.io.gltf.load.MAX_JSON_BYTES", 1000)
    path = tmp_path / "big.gltf"
    path.write_text(json.dumps({"asset": {"version": "2.0"}, "nodes": [{"name": "x" * 2000}]}), encoding="utf-8")
    with pytest.raises(GltfError, match="bytes of JSON; gsik reads at most 1,000"):
        read_gltf(path)


def test_a_cycle_in_the_nodes_is_refused(biped_gltf, tmp_path):
    doc = json.loads(json.dumps(biped_gltf))
    doc["nodes"][0]["children"] = doc["nodes"][0].get("children", []) + [3]  # node 3 is a grandchild of node 0 ...
    doc["nodes"][3]["children"] = [0]
    with pytest.raises(GltfError, match="child twice|cycle"):
        read_gltf(_write(tmp_path, doc))
    doc = json.loads(json.dumps(biped_gltf))
    doc["nodes"][1]["children"] = doc["nodes"][1].get("children", []) + [1]
    with pytest.raises(GltfError, match="child twice|cycle"):
        read_gltf(_write(tmp_path, doc))


@pytest.mark.parametrize("content", [b"", b"glTF\x02\x00\x00\x00\xff\xff\xff\x7f", b"{not json", b"[]",
                                     b'{"asset": {"version": "2.0"}, "nodes": "x"}'])
def test_garbage_is_one_gltf_error(tmp_path, content):
    path = tmp_path / "garbage.glb"
    path.write_bytes(content)
    with pytest.raises(GsikError):
        read_gltf(path)


def test_export_of_a_bad_character_writes_nothing_and_keeps_an_existing_file(biped_gltf, tmp_path, capsys):
    doc = json.loads(json.dumps(biped_gltf))
    doc["nodes"][1]["children"] = [1]
    bad = _write(tmp_path, doc, "bad.gltf")
    assert main(["export-gltf", POSE, "--out", str(tmp_path / "good.glb")]) == 0
    out = tmp_path / "out.glb"
    assert main(["export-gltf", POSE, "--character", str(bad), "--out", str(out)]) == 2
    assert not out.exists() and "child twice" in capsys.readouterr().err
    out.write_bytes(b"precious")
    assert main(["export-gltf", POSE, "--character", str(bad), "--out", str(out)]) == 2
    assert out.read_bytes() == b"precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.gltf", "good.glb", "out.glb"]  # no temporary left
