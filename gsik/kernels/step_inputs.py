"""A controller's fixed step inputs held by one compiled object, so a step's call passes 7 arguments, not ~70 arrays.

:func:`gsik.kernels.accept.control_step` takes 23 arguments, NamedTuples of ~70 arrays in all, and numba unboxes every
array on every call: ~8.5 µs, ~12 right after the previous step's kernel (timed as a no-op kernel given the same
arguments). All but the pose, the root's transform and the damping are fixed for a controller's targets' weights,
so :func:`make_step_inputs` packs them once into a :class:`StepInputs` (a numba structure: one pointer to unbox), and
:func:`control_step` calls the kernel with them.
"""

from __future__ import annotations

import math

from gsik._jit import njit
from gsik.kernels import accept as ak

#: What a :class:`StepInputs` holds, in :func:`gsik.kernels.accept.control_step`'s order around the per-step
#: arguments (``W`` after ``root``; ``q``, ``R``, ``p``, ``lam``, ``damping`` after ``max_step``).
FIELDS = ("task_model", "fk", "tasks", "posture", "root", "lower", "upper", "max_step", "base", "near", "tols",
          "floors", "rule", "restoring", "stall_tolerance", "cache", "window", "wk")

@njit(cache=True)
def norm(v):
    """``sqrt(sum(v ** 2))`` [rad] of a step ``v`` (n,), summed in order: every controlled step's norm, whether the
    compiled call committed it (:func:`control_step`) or the controller's Python branches did, is this one sum."""
    s = 0.0
    for d in range(v.shape[0]):
        s += v[d] * v[d]
    return math.sqrt(s)


#: False without numba or with ``NUMBA_DISABLE_JIT``: the controller then calls the kernel with every argument.
AVAILABLE = hasattr(ak.control_step, "overloads")

if AVAILABLE:
    from numba.core import types
    from numba.experimental import structref

    @structref.register
    class StepInputsType(types.StructRef):
        """The numba type of a :class:`StepInputs`: its fields' types as given (no literals)."""

        def preprocess_fields(self, fields):
            return tuple((name, types.unliteral(typ)) for name, typ in fields)

    class StepInputs(structref.StructRefProxy):
        """A controller's fixed inputs of :func:`gsik.kernels.accept.control_step` (:data:`FIELDS`)."""

    structref.define_proxy(StepInputs, StepInputsType, list(FIELDS))

    @njit(cache=True)
    def make_step_inputs(task_model, fk, tasks, posture, root, lower, upper, max_step, base, near, tols, floors, rule,
                         restoring, stall_tolerance, cache, window, wk):
        """A :class:`StepInputs` of these (made by compiled code, which is cached: no compiling per process)."""
        return StepInputs(task_model, fk, tasks, posture, root, lower, upper, max_step, base, near, tols, floors, rule,
                          restoring, stall_tolerance, cache, window, wk)

    @njit(cache=True)
    def control_step(inputs, W, q, R, p, lam, damping):
        """:func:`gsik.kernels.accept.control_step` from ``q`` (n,) [rad] at ``W`` (4, 4) (frames ``R``, ``p``;
        ``lam`` (1,) the adaptive damping, ``damping`` this step's) with a controller's fixed ``inputs``
        (:func:`make_step_inputs`). Returns what a committed step's statistics need, read from the cache's ``out``
        and ``flags``: ``(R_STATUS, R_COMMITTED, R_CREEPS, F_CONVERGED, F_TARGET_COST, F_LAGGING)``, then the
        committed step's :func:`norm` [rad] (of ``cache.moved``)."""
        s = inputs
        ak.control_step(s.task_model, s.fk, s.tasks, s.posture, s.root, W, s.lower, s.upper, s.max_step, q, R, p,
                        lam, damping, s.base, s.near, s.tols, s.floors, s.rule, s.restoring, s.stall_tolerance,
                        s.cache, s.window, s.wk)
        out, flags = s.cache.out, s.cache.flags
        return (out[ak.R_STATUS], out[ak.R_COMMITTED], out[ak.R_CREEPS], flags[ak.F_CONVERGED],
                flags[ak.F_TARGET_COST], flags[ak.F_LAGGING], norm(s.cache.moved))
