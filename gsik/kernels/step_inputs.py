"""A controller's fixed step inputs held by one compiled object, so a step's call passes 7 arguments, not ~70 arrays.

:func:`gsik.kernels.accept.control_step` takes 23 arguments, NamedTuples of ~70 arrays in all, and numba unboxes every
array on every call: ~8.5 µs, ~12 right after the previous step's kernel (timed as a no-op kernel given the same
arguments). All but the pose, the root's transform and the damping are fixed for a controller's targets' weights,
so :func:`make_step_inputs` packs them once into a :class:`StepInputs` (a numba structure: one pointer to unbox), and
:func:`control_step` calls the kernel with them.
"""

from __future__ import annotations

from gsik._jit import njit
from gsik.kernels import accept as ak
from gsik.kernels import fallback as fb
from gsik.kernels.accept import creeps
from gsik.kernels.accept import norm  # noqa: F401  (every controlled step's norm, as before)

#: What a :class:`StepInputs` holds, in :func:`gsik.kernels.accept.control_step`'s order around the per-step
#: arguments (``W`` after ``root``; ``q``, ``R``, ``p``, ``lam``, ``damping`` after ``max_step``).
FIELDS = ("task_model", "fk", "tasks", "posture", "root", "lower", "upper", "max_step", "base", "near", "tols",
          "floors", "rule", "restoring", "stall_tolerance", "cache", "window", "wk")

#: False without numba or with ``NUMBA_DISABLE_JIT``: the controller then calls the kernel with every argument.
AVAILABLE = hasattr(ak.control_step, "overloads")

if AVAILABLE:
    from numba.core import types
    from numba.experimental import structref

    from gsik.kernels.borrow import borrow

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
        """:func:`control_step_in` for a caller that holds references (Python, a kernel compiled with NRT)."""
        return control_step_in(inputs, W, q, R, p, lam, damping)

    @njit(cache=True, _nrt=False)
    def control_step_in(inputs, W, q, R, p, lam, damping):
        """:func:`gsik.kernels.fallback.control_step` (the full step and, when refused, its fallback) from ``q``
        (n,) [rad] at ``W`` (4, 4) (frames ``R``, ``p``; ``lam`` (1,) the adaptive damping, ``damping`` this
        step's) with a controller's fixed ``inputs`` (:func:`make_step_inputs`), its fields read without reference
        counting (:func:`gsik.kernels.borrow.borrow`). Returns :func:`gsik.kernels.fallback.step_end`: what the
        step's statistics need."""
        s = inputs
        fb.control_step(borrow(s, "task_model"), borrow(s, "fk"), borrow(s, "tasks"), borrow(s, "posture"),
                        borrow(s, "root"), W, borrow(s, "lower"), borrow(s, "upper"), borrow(s, "max_step"), q, R, p,
                        lam, damping, borrow(s, "base"), borrow(s, "near"), borrow(s, "tols"), borrow(s, "floors"),
                        borrow(s, "rule"), borrow(s, "restoring"), borrow(s, "stall_tolerance"), borrow(s, "cache"),
                        borrow(s, "window"), borrow(s, "wk"))
        return fb.step_end(borrow(s, "cache"))

    @njit(cache=True, _nrt=False)
    def judged_in(inputs, end, posture_on):
        """``(accepted, held, step_norm)`` of a step that ended in ``end`` (what :func:`control_step` returns), as
        ``gsik.control.Controller`` judges it: a committed step holds when its norm [rad] is at most the stall
        tolerance or the stall window says it creeps (asked here when the kernel left it to that norm); a refused
        one as the kernel said."""
        if end[1] > 0.0:  # committed: gsik.control.Controller._committed
            step_norm, crept, stall = end[6], end[2], borrow(inputs, "stall_tolerance")
            if crept < 0.0:
                cache = borrow(inputs, "cache")
                crept = 1.0 if not step_norm <= stall and creeps(borrow(inputs, "window"), cache.met, posture_on,
                                                                 cache.costs) else 0.0
            return True, step_norm <= stall or crept > 0.0, step_norm
        return False, end[2] > 0.0, 0.0
