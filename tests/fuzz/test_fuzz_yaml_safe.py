"""The bounded YAML reader: the data and lines yaml.safe_load would give for plain files, a clear refusal otherwise."""

from __future__ import annotations

import math
import random

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from fuzzing import HOSTILE, TOKENS, mutate, seeds
from gsik.errors import GsikError, PoseError, SkeletonError
from gsik.io.yaml_safe import MAX_CHARS, MAX_DEPTH, MAX_INT, load_yaml, yaml_string
from gsik.errors import MAX_VALUE_CHARS, choices, show_value


def _refusal(text: str) -> str:
    with pytest.raises(PoseError) as info:
        load_yaml(text, "f.yaml", PoseError)
    return str(info.value)


# -- plain files read as yaml.safe_load reads them ----------------------------------

def _reference_lines(node, path=(), lines=None) -> dict:
    """The line map the pose reader used to build by walking the composed node graph."""
    lines = {} if lines is None else lines
    lines[path] = node.start_mark.line + 1
    if isinstance(node, yaml.MappingNode):
        for key_node, value_node in node.value:
            key = yaml.safe_load(yaml.serialize(key_node))
            _reference_lines(value_node, path + (key,), lines)
            lines[path + (key,)] = key_node.start_mark.line + 1
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            _reference_lines(item, path + (i,), lines)
    return lines


_scalars = (st.none() | st.booleans() | st.integers(-MAX_INT, MAX_INT)
            | st.floats(allow_nan=False, width=64) | st.text(st.characters(blacklist_categories=("Cs",)), max_size=12))
_keys = st.text(st.characters(blacklist_categories=("Cs",)), min_size=1, max_size=8) | st.integers(-99, 99)
_documents = st.recursive(_scalars, lambda inner: st.lists(inner, max_size=4)
                          | st.dictionaries(_keys, inner, max_size=4), max_leaves=25)


@settings(max_examples=150, deadline=None)
@given(_documents, st.booleans())
def test_plain_documents_read_as_safe_load_reads_them(data, flow):
    text = yaml.safe_dump(data, default_flow_style=flow, allow_unicode=True)
    doc = load_yaml(text, "f.yaml", PoseError)
    assert doc.data == yaml.safe_load(text)
    assert doc.lines == _reference_lines(yaml.compose(text, Loader=yaml.SafeLoader))


def test_seed_files_read_as_safe_load_reads_them():
    for kind in ("pose", "skeleton"):
        text = seeds()[kind][0]
        doc = load_yaml(text, "f.yaml", PoseError)
        assert doc.data == yaml.safe_load(text)
        assert doc.lines == _reference_lines(yaml.compose(text, Loader=yaml.SafeLoader))


def test_an_empty_file_is_none_and_plain_dates_stay_dates():
    assert load_yaml("", "f.yaml", PoseError).data is None
    assert load_yaml("# just a comment\n", "f.yaml", PoseError).data is None
    assert load_yaml("a: 2001-12-14", "f.yaml", PoseError).data == yaml.safe_load("a: 2001-12-14")


def test_aliases_of_shared_data_read_as_safe_load_reads_them():
    shared = [1.5, [2, 3]]
    text = yaml.safe_dump({"a": shared, "b": [shared, {"c": shared}]})
    assert "*id001" in text
    doc = load_yaml(text, "f.yaml", PoseError)
    assert doc.data == yaml.safe_load(text)
    assert doc.lines[("b", 0)] == 6 and ("b", 0, 1) not in doc.lines  # inside an alias: the alias's line


def test_names_yaml_cannot_construct_read_as_text():
    assert load_yaml("a: =\n'=': b\n", "f.yaml", PoseError).data == {"a": "=", "=": "b"}


# -- what is refused, with file and line ----------------------------------------------

@pytest.mark.parametrize("name, line, words", [
    ("alias_bomb_pose.yaml", 10, "more than 1,000,000 values (counting what aliases repeat)"),
    ("alias_bomb_skeleton.yaml", 9, "more than 1,000,000 values (counting what aliases repeat)"),
    ("self_alias.yaml", 2, "alias *s refers to a list or mapping it is inside of"),
    ("deep_nesting.yaml", 3, f"nested deeper than {MAX_DEPTH} levels"),
    ("deep_mapping.yaml", 35, f"nested deeper than {MAX_DEPTH} levels"),
    ("huge_int_pose.yaml", 1, "is too large"),
    ("huge_float.yaml", 5, "is too large for a float"),
    ("python_tag.yaml", 2, "tag 'tag:yaml.org,2002:python/object/apply:os.system' is not allowed"),
    ("custom_tag.yaml", 2, "tag '!shout' is not allowed"),
    ("merge_key.yaml", 4, "merge keys ('<<') are not allowed"),
    ("two_documents.yaml", 3, "one YAML document"),
    ("nul_byte.yaml", 2, "character U+0000 is not allowed"),
])
def test_hostile_files_are_refused_naming_file_and_line(name, line, words):
    text = (HOSTILE / name).read_text(encoding="utf-8")
    with pytest.raises(SkeletonError) as info:
        load_yaml(text, name, SkeletonError)
    message = str(info.value)
    assert message.startswith(f"{name}:{line}: ")
    assert words in message
    assert len(message) < 300


@pytest.mark.parametrize("text, words", [
    ("a: " + "9" * 5000, "is too large"),  # beyond Python's int-from-text limit: no raw ValueError
    (f"a: {MAX_INT + 1}", "is too large"),
    (f"a: -{MAX_INT + 1}", "is too large"),
    ("a: 0x" + "f" * 17, "is too large"),
    ("a: -1.0e+400", "is too large for a float"),
    ("a: 2001-13-45", "cannot read '2001-13-45' as timestamp"),
    ("a: 1\na: 2", "duplicate key 'a' (first at line 1)"),
    ("? [a]\n: 1", "a mapping key must be a plain value"),
    ("a: !!binary aGk=", "is not allowed"),
    ("a: !!set {b}", "is not allowed"),
    ("a: [1, 2", "not valid YAML"),
    ("a: b: c", "not valid YAML"),
    ("a: \x85\x7f", "character U+007F is not allowed"),
])
def test_values_yaml_would_mishandle_are_refused(text, words):
    assert words in _refusal(text)


def test_edge_values_are_read():
    doc = load_yaml(f"a: {MAX_INT}\nb: -{MAX_INT}\nc: 1.7e+308\nd: .inf\ne: .nan\n", "f.yaml", PoseError)
    assert doc.data["a"] == MAX_INT and doc.data["b"] == -MAX_INT and doc.data["c"] == 1.7e308
    assert doc.data["d"] == math.inf and math.isnan(doc.data["e"])


def test_nesting_up_to_the_limit_is_read_and_one_deeper_is_refused():
    assert load_yaml("[" * MAX_DEPTH + "]" * MAX_DEPTH, "f.yaml", PoseError).data is not None
    assert f"deeper than {MAX_DEPTH}" in _refusal("[" * (MAX_DEPTH + 1) + "]" * (MAX_DEPTH + 1))


def test_deep_nesting_far_past_the_recursion_limit_is_refused():
    assert "deeper than" in _refusal("[" * 200_000)
    assert "deeper than" in _refusal("".join("  " * i + "- \n" for i in range(2000)))


def test_text_over_the_size_limit_is_refused_before_parsing():
    message = _refusal("#" * (MAX_CHARS + 1))
    assert message == f"f.yaml: file is {MAX_CHARS + 1:,} characters long; the limit is {MAX_CHARS:,}"


def test_a_long_value_is_cut_in_the_message():
    long = "n" * 1_000_000
    message = _refusal(f"a: 1\n? {long}\n: 1\n? {long}\n: 2\n")  # explicit keys: plain ones stop at 1024
    assert message.startswith("f.yaml:4: duplicate key 'nnnn")
    assert len(message) < 200


def test_the_error_type_is_the_callers():
    with pytest.raises(SkeletonError, match=r"^s\.yaml:1: alias \*b refers to no anchor before it$"):
        load_yaml("a: *b", "s.yaml", SkeletonError)
    with pytest.raises(PoseError, match="must be a str"):
        load_yaml(b"a: 1", "s.yaml", PoseError)


# -- mutated files: read or refused, nothing else ------------------------------------------

def test_mutated_gsik_files_are_read_or_refused_as_gsik_errors():
    rng = random.Random(11)
    texts = seeds()["pose"] + seeds()["skeleton"]
    counts = {"read": 0, "refused": 0}
    for _ in range(600):
        text = mutate(rng.choice(texts), TOKENS["yaml"], rng)
        try:
            load_yaml(text, "m.yaml", SkeletonError)
            counts["read"] += 1
        except GsikError as exc:
            assert str(exc).startswith("m.yaml"), str(exc)[:200]
            assert len(str(exc)) < 400
            counts["refused"] += 1
    assert counts["read"] > 100 and counts["refused"] > 100, counts  # both paths exercised


# -- names of any characters written so they read back exactly ------------------------------------------------

@settings(max_examples=300, deadline=None)
@given(st.text(max_size=300))
def test_any_name_is_written_so_it_reads_back_exactly_as_key_and_value(name):
    text = yaml_string(name)
    assert "\n" not in text and "\r" not in text
    assert load_yaml(f"{text}: {text}\n", "n.yaml", PoseError).data == {name: name}
    assert load_yaml(f"- {text}\n", "n.yaml", PoseError).data == [name]


@pytest.mark.parametrize("name", ["[root]", "{x}", "'q", '"d', "|p", ">g", "%h", "@at", "`t", "a: b", "#c", "-", "- x",
                                  "*star", "&amp", "!bang", "? q", "=", "~", "null", "Null", "true", "on", "No", "1.5",
                                  "0x10", "1e3", "2001-12-14", "<<", "", " lead", "trail ", "tab\t", "new\nline",
                                  "\x85", "\u2028", "\u2029", "\ufeffbom", "\x00", "\x7f", "\U0001F9B4", "caf\u00e9", "..."])
def test_names_yaml_would_misread_are_quoted_and_read_back(name):
    assert load_yaml(f"{yaml_string(name)}: 1\n", "n.yaml", PoseError).data == {name: 1}


def test_plain_names_stay_plain():
    assert [yaml_string(n) for n in ("left_hand", "waist.x", "Hips", "j-1")] == ["left_hand", "waist.x", "Hips", "j-1"]


# -- bounded message values ----------------------------------------------------------

@pytest.mark.parametrize("value", ["n" * 20_000_000, list(range(1_000_000)), {i: [i] * 1000 for i in range(1000)},
                                   10**4000, b"\x00" * 10**6, "é" * 100],
                         ids=["20M str", "1M list", "nested dict", "4000 digits", "1M bytes", "accents"])
def test_show_value_is_bounded(value):
    text = show_value(value)
    assert len(text) <= MAX_VALUE_CHARS
    assert text[:4] == repr(value)[:4] if not isinstance(value, int) else text[:4] == "1000"


def test_show_value_quotes_short_values_whole():
    assert show_value("left_hand") == "'left_hand'"
    assert show_value([1.5, None]) == "[1.5, None]"
    nested = []
    nested.append(nested)
    assert len(show_value(nested)) <= MAX_VALUE_CHARS


def test_show_value_survives_a_hostile_repr():
    class Hostile:
        def __repr__(self):
            raise RuntimeError("no")

    assert show_value(Hostile()).startswith("<Hostile")


def test_choices_lists_a_few_and_counts_the_rest():
    assert choices(["a", "b"]) == "'a', 'b'"
    text = choices(f"j{i}" for i in range(100_000))
    assert text.endswith("... and 99940 more") and len(text) < 600
