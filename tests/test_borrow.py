"""A structure's field read without reference counting (gsik.kernels.borrow): the field itself, in kernels compiled
with and without NRT, and the references balanced."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from gsik.kernels import step_inputs

if not step_inputs.AVAILABLE:  # pragma: no cover - numba missing or NUMBA_DISABLE_JIT
    pytest.skip("borrow is a numba intrinsic: nothing is compiled here", allow_module_level=True)

from numba import njit
from numba.core import cgutils, types
from numba.core.errors import TypingError
from numba.experimental import structref
from numba.extending import intrinsic

from gsik.kernels.borrow import borrow


@structref.register
class _PairType(types.StructRef):
    def preprocess_fields(self, fields):
        return tuple((name, types.unliteral(typ)) for name, typ in fields)


class _Pair(structref.StructRefProxy):
    pass


structref.define_proxy(_Pair, _PairType, ["rows", "parts", "scale"])


@njit
def _make(rows, parts, scale):
    return _Pair(rows, parts, scale)


@njit(_nrt=False)
def _read_bare(pair, i):
    """Reads through borrow where numba takes no references (a field read itself is refused here)."""
    rows, parts = borrow(pair, "rows"), borrow(pair, "parts")
    return rows[i, 0] + parts[0][i] + parts[1][0] * borrow(pair, "scale")


@njit
def _read_counted(pair, i):
    rows, parts = borrow(pair, "rows"), borrow(pair, "parts")
    return rows[i, 0] + parts[0][i] + parts[1][0] * borrow(pair, "scale")


@njit
def _read_attr(pair, i):
    return pair.rows[i, 0] + pair.parts[0][i] + pair.parts[1][0] * pair.scale


@njit(_nrt=False)
def _write_bare(pair, value):
    borrow(pair, "rows")[0, 0] = value


def _arrays():
    return np.arange(12.0).reshape(4, 3), (np.arange(4.0) * 10.0, np.array([0.5]))


def test_it_reads_the_field_itself_with_and_without_nrt():
    rows, parts = _arrays()
    pair = _make(rows, parts, 3.0)
    for i in range(4):
        expected = rows[i, 0] + parts[0][i] + parts[1][0] * 3.0
        assert _read_bare(pair, i) == expected == _read_counted(pair, i) == _read_attr(pair, i)
    _write_bare(pair, -7.0)  # the structure's own array, not a copy
    assert rows[0, 0] == -7.0


@intrinsic
def _references(typingctx, array):
    """The reference count of ``array``'s NRT MemInfo (its first word)."""

    def codegen(context, builder, signature, args):
        meminfo = cgutils.create_struct_proxy(array)(context, builder, value=args[0]).meminfo
        return builder.load(builder.bitcast(meminfo, context.get_value_type(types.intp).as_pointer()))

    return types.intp(array), codegen


@njit(_nrt=False)
def _counts(pair):
    return _references(borrow(pair, "rows")), _references(borrow(pair, "parts")[0])


def test_its_references_are_balanced_with_and_without_nrt():
    """A kernel with NRT takes a field read's reference and gives it back; one without takes none."""
    pair = _make(*_arrays(), 1.0)
    before = _counts(pair)
    assert before[0] >= 1 and before[1] >= 1
    for _ in range(1000):
        _read_bare(pair, 1)
        _read_counted(pair, 2)
        _read_attr(pair, 3)
    assert _counts(pair) == before


def test_a_name_it_does_not_hold_or_not_a_literal_is_refused_when_compiling():
    pair = _make(*_arrays(), 1.0)

    @njit(_nrt=False)
    def unknown(pair):
        return borrow(pair, "missing")

    @njit(_nrt=False)
    def not_literal(pair, name):
        return borrow(pair, name)

    with pytest.raises(TypingError):
        unknown(pair)
    with pytest.raises(TypingError):
        not_literal(pair, "rows")


_PLAIN_STEP = """
import json
import os
import gsik
from collections import namedtuple
from gsik.kernels.borrow import borrow
s = gsik.Solver(gsik.load_skeleton("biped"))
t = {n: gsik.Target.from_transform(T) for n, T in s.effector_poses().items()}
t["left_hand"] = t["left_hand"].replace(position=t["left_hand"].position + [0.0, 0.05, 0.02])
for _ in range(3):
    s.step(t)
python = os.environ.get("NUMBA_DISABLE_JIT") == "1"  # compiled, borrow is an intrinsic: not callable from Python
field = borrow(namedtuple("Pair", "rows")(7.0), "rows") if python else None
print(json.dumps({"field": field, "q": s.q.tolist()}))
"""


def test_without_the_compiler_it_is_the_attribute_and_the_plain_step_the_same():
    """``NUMBA_DISABLE_JIT``: the kernels run as Python, ``borrow`` is ``getattr``, and the plain step (its fields read
    through it) gives the compiled step's angles."""
    runs = []
    for extra in ({"NUMBA_DISABLE_JIT": "1"}, {}):
        env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")} | extra
        out = subprocess.run([sys.executable, "-c", _PLAIN_STEP], env=env, capture_output=True, text=True, check=False)
        assert out.returncode == 0, out.stderr[-2000:]
        runs.append(json.loads(out.stdout.splitlines()[-1]))
    python, compiled = runs
    assert python["field"] == 7.0
    np.testing.assert_allclose(python["q"], compiled["q"], atol=1e-9)
