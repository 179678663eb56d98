"""A single-level result's arrays, copies of the solver's state, reusing a previous result's once nothing holds them.

A tracked chain's frame made a copy of the state (angles, then the position and orientation errors) and three views
of it for every :class:`~gsik.result.SolveResult`: about 1.2 µs of an arm's 13 µs frame. A result the caller has
dropped (the usual frame: ``r = solver.step()`` replaces the one before) leaves its arrays held by the solver alone;
:class:`ResultArrays` then writes the new state into them (one ``memcpy``) instead of making new ones. It keeps two
sets in turn, since the caller still holds the last result while the next step runs. Whether a set is free is read
from reference counts: every holder of the copy or of any of its views (a result, an array viewing them, a
``memoryview``, a ``base``) adds to one of them, so a set anything else holds is never written again, and a result
never changes when the solver moves on. The counts a free set has are measured once, on a set just made.
"""

from __future__ import annotations

from sys import getrefcount

import numpy as np


def _counts(arrays: list) -> tuple[int, int, int, int]:
    """Reference counts of a set's copy and its three views (the same code reads them for a free set and for one
    in question, so the interpreter's own references count the same)."""
    return getrefcount(arrays[1]), getrefcount(arrays[2]), getrefcount(arrays[3]), getrefcount(arrays[4])


class ResultArrays:
    """Copies of ``state`` (n + 2 m,) float64, contiguous: ``take()`` returns ``(q (n,), position errors (m,),
    orientation errors (m,))``, views of one copy of its values now, reusing a set no one else holds."""

    def __init__(self, state: np.ndarray, slices: tuple[slice, slice, slice]):
        self._state, self._slices = state, slices
        self._source = memoryview(state).cast("B")
        self._sets = [self._new_set(), self._new_set()]
        self._free = _counts(self._sets[0])
        self._turn = 0

    def _new_set(self) -> list:
        """``[the copy's bytes, the copy, q, position errors, orientation errors]`` of the state now."""
        out = self._state.copy()
        q, pos, ori = self._slices
        return [memoryview(out).cast("B"), out, out[q], out[pos], out[ori]]

    def take(self) -> list:
        """``[bytes, copy, q, position errors, orientation errors]`` (read the last three): the state's values
        now, in arrays no one else holds."""
        turn = self._turn
        self._turn = 1 - turn
        arrays = self._sets[turn]
        if _counts(arrays) == self._free:
            arrays[0][:] = self._source
            return arrays
        arrays = self._sets[turn] = self._new_set()  # the caller kept them: they are its now
        return arrays
