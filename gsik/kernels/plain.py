"""The single-level step's and solve's inputs held by one compiled object: a call from Python unboxes one pointer.

A step over the two buffers of :mod:`gsik.kernels.buffers` unboxed them and cut them into the named contracts on
every call (about 1 µs of an arm's 9 µs frame step: some thirty slices and reshapes), and
:func:`gsik.kernels.solve.solve` took 23 arrays from Python. A :class:`PlainInputs` holds those contracts, cut once
from the same buffers (the :class:`~gsik.solver.Solver`'s NumPy views see the same memory), with both calls'
settings and the step's :class:`~gsik.kernels.Scratch`; :func:`step_plain` and :func:`solve_plain` run the same
kernels on them and return the statistics a result needs as numbers (:data:`PLAIN_STATS`) (reading them back from ``ws.stats`` in
Python costs more than the call). The same numbers as the kernels called field by field.
"""

from __future__ import annotations

from typing import NamedTuple

from gsik._jit import njit
from gsik.kernels import CONVERGED, O_COST, O_FINITE, O_ITERATIONS, O_RESIDUAL, O_STATUS, O_STEP_NORM, O_SWEEPS
from gsik.kernels.borrow import borrow
from gsik.kernels.buffers import views
from gsik.kernels.solve import solve
from gsik.kernels.step import step_with

#: What a :class:`PlainInputs` holds: the step's and the solve's :class:`~gsik.kernels.KernelSettings`, then
#: :func:`gsik.kernels.buffers.views`'s contracts (``root`` the IK root's frame).
FIELDS = ("settings", "solve_settings", "model", "targets", "root", "W", "q", "ws", "sc")


#: The order of what :func:`step_plain` and :func:`solve_plain` return, a plain tuple (numba boxes a NamedTuple
#: through its Python constructor: 2 µs a call, against 0.3 for a tuple): ``finite`` (False: the step or attempt was
#: not taken, ``ws.stats[O_FINITE]`` 0), the :class:`~gsik.Status` code, iterations, sweeps, the residual (a step's
#: projected ``|Ax - b|``, a solve's weighted error) and the step's norm [rad].
PLAIN_STATS = ("finite", "status", "iterations", "sweeps", "residual", "step_norm")


try:
    from numba.core import types
    from numba.experimental import structref
except ImportError:  # pragma: no cover - exercised only without numba
    structref = None

#: False without numba or with ``NUMBA_DISABLE_JIT``: :class:`PlainInputs` is then a plain NamedTuple.
AVAILABLE = structref is not None and hasattr(step_with, "overloads")

if AVAILABLE:

    @structref.register
    class PlainInputsType(types.StructRef):
        """The numba type of a :class:`PlainInputs`: its fields' types as given (no literals)."""

        def preprocess_fields(self, fields):
            return tuple((name, types.unliteral(typ)) for name, typ in fields)

    class PlainInputs(structref.StructRefProxy):
        """A solver's single-level kernel inputs (:data:`FIELDS`), over its buffers."""

    structref.define_proxy(PlainInputs, PlainInputsType, list(FIELDS))
else:  # pragma: no cover - exercised only without numba
    PlainInputs = NamedTuple("PlainInputs", [(name, object) for name in FIELDS])


@njit(cache=True)
def make_plain_inputs(settings, solve_settings, floats, ints, sizes):
    """A :class:`PlainInputs` over the buffers of :func:`gsik.kernels.buffers.make_buffers` (made by compiled code,
    which is cached: no compiling per process)."""
    model, targets, W, q, ws, sc = views(floats, ints, sizes)
    return PlainInputs(settings, solve_settings, model, targets, sizes.root, W, q, ws, sc)


@njit(cache=True)
def step_plain(s):
    """:func:`gsik.kernels.step.step` on ``s`` (a :class:`PlainInputs`); returns its :data:`PLAIN_STATS`."""
    return _step_plain(s)


@njit(cache=True, _nrt=False)
def _step_plain(s):
    """:func:`step_plain`, the fields of ``s`` read without reference counting (:func:`gsik.kernels.borrow.borrow`:
    ~80 atomic reference counts a call fewer)."""
    ws = borrow(s, "ws")
    finite = step_with(borrow(s, "model"), borrow(s, "settings"), borrow(s, "targets"), borrow(s, "root"),
                       borrow(s, "W"), borrow(s, "q"), ws, borrow(s, "sc"))
    st = ws.stats
    return finite, int(st[O_STATUS]), int(st[O_ITERATIONS]), int(st[O_SWEEPS]), st[O_RESIDUAL], st[O_STEP_NORM]


@njit(cache=True)
def solve_plain(s, max_iterations, finish):
    """One attempt of :func:`gsik.kernels.solve.solve` on ``s`` from its angles, at most ``max_iterations``
    linearisations; returns its :data:`PLAIN_STATS` (the residual the weighted error). With ``finish``, an attempt
    that converged (finite) also leaves what a finished solve leaves: no warm step (``ws.x`` 0) and the damping
    reset (the attempt itself reads and writes neither)."""
    ws = s.ws
    solve(s.model, s.solve_settings, s.targets, s.root, s.W, s.q, max_iterations, ws)
    st = ws.stats
    finite = st[O_FINITE] != 0.0
    status = int(st[O_STATUS])
    if finish and finite and status == CONVERGED:
        ws.x[:] = 0.0
        ws.lam[0] = s.settings.damping
    return finite, status, int(st[O_ITERATIONS]), int(st[O_SWEEPS]), st[O_COST], st[O_STEP_NORM]
