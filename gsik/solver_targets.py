"""How a :class:`~gsik.solver.Solver` takes its targets: replaced all at once, set one by one, or moved in place
each frame. A mixin of :class:`~gsik.solver.Solver`, which owns the state it works on (``_pack_targets`` writes
the targets into the kernels' rows)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from gsik import kernels
from gsik.errors import TargetError, choices
from gsik.kernels.buffers import target_rows_at
from gsik.kernels.targets import WRITTEN, move_pose_at, move_position_at
from gsik.targets import PACK3_INTO, PACK9_INTO, Target, checked_position, checked_rotation

#: Most enabled targets a solver takes at once (a tracked 100-joint clip uses about 200).
MAX_TARGETS = 512
#: Most distinct priority levels among them.
MAX_PRIORITY_LEVELS = 16
#: float64 (native byte order): the dtype a moved target's arrays need for the compiled write.
_F8 = np.dtype(np.float64)
#: Arrays of any layout (a column of a transform is strided): what the compiled entry is made for.
_ANY_VECTOR, _ANY_MATRIX = np.zeros((3, 2))[:, 0], np.zeros((3, 6))[:, ::2]
#: What a target moved with a rotation matrix records in ``_moved``: no quaternion given, its rotation turned.
_TURNED = (None, True)


class TargetSetting:
    """:meth:`set_targets`, :meth:`set_target` and :meth:`move_target`, for :class:`~gsik.solver.Solver`.

    A moved target is written straight into the kernels' rows; the :class:`Target` it stands for is made only when
    something reads the targets (:attr:`targets`, a solve, a change of targets), so a frame that only moves and
    steps makes none.
    """

    @property
    def _targets(self) -> dict[str, Target]:
        """The enabled targets by name, the moves made since they were last read included."""
        if self._moved:
            self._make_moved_targets()
        return self._target_map

    def _make_moved_targets(self) -> None:
        """The :class:`Target` of each target moved since the targets were last read, from its packed row: called
        before anything stages other values in the rows (a solve's continuation)."""
        tp, tR = self._packed.position, self._packed.rotation
        for name, (q, turned) in self._moved.items():
            k = self._row_of[name]
            rows = tuple(tR[k].ravel().tolist()) if turned else None
            self._target_map[name] = self._target_map[name]._moved_to(tuple(tp[k].tolist()), q, rows)
        self._moved.clear()

    @_targets.setter
    def _targets(self, targets: dict[str, Target]) -> None:
        self._moved = {}
        self._target_map = targets

    @property
    def targets(self) -> dict[str, Target]:
        """The current targets (a new dict; targets themselves are immutable)."""
        return dict(self._targets)

    def set_targets(self, targets: Mapping[str, Target | None]) -> None:
        """Replace all targets. An effector with no target (``None``, or a disabled one) is free.

        Raises:
            TargetError: for a name that is not one of :attr:`effector_names`
                (the root cannot have a target) or a value that is not a
                :class:`Target`. Nothing changes when it raises.
        """
        checked, layout = self._check_targets(targets)
        self._moved, self._target_map = {}, checked  # the _targets setter's, without its call (a frame's every call)
        self._pack_targets(layout)

    def set_target(self, name: str, target: Target | None) -> None:
        """Set or (with ``None``) remove one effector's target."""
        checked = self._check_targets({name: target})[0]
        _check_target_counts({**{n: t for n, t in self._targets.items() if n != name}, **checked})
        self._targets.pop(name, None)
        self._targets.update(checked)
        self._pack_targets()

    def move_target(self, name: str, position, orientation=None) -> None:
        """Move the target of ``name`` in place: the per-frame call of a drag or a tracked trajectory.

        The same as ``set_target(name, target.replace(position=position, orientation=orientation))`` (its
        weight, flags and priority kept), for less: on the single-level path the new position and orientation go
        straight into the kernels' rows, and the :class:`Target` is made only when the targets are next read.

        Args:
            name: An effector (or joint or site) that has an enabled target.
            position: World position (3,) [m].
            orientation: World orientation, a rotation matrix (3, 3) or a unit quaternion (4,) ``(w, x, y, z)``;
                ``None`` keeps the target's orientation.

        Raises:
            TargetError: for a name with no target (or not a target name at all), or a position or
                orientation that ``Target`` refuses (NaN, infinite, not a rotation ...). Nothing changes when it
                raises.
        """
        rows = self._fast_rows
        at = (self._make_fast_rows() if rows is None else rows).get(name)  # None: not on the single level's rows
        if at is not None and type(position) is np.ndarray and position.dtype is _F8 and position.ndim == 1:
            # The usual frame: float arrays that pass Target's checks as they are go straight into the row (the
            # compiled call checks their lengths, finiteness and bounds; Python only what unboxing needs).
            position_at, pose_at, floats, p_at, R_at = at
            if orientation is None:
                if position_at(position, floats, p_at) == WRITTEN:
                    if name not in self._moved:
                        self._moved[name] = (None, False)
                    return
            elif type(orientation) is np.ndarray and orientation.dtype is _F8 and orientation.ndim == 2 \
                    and pose_at(position, orientation, floats, p_at, R_at) == WRITTEN:
                self._moved[name] = _TURNED
                return
        self._move_checked(name, position, orientation)

    def _write_target_rows(self) -> None:
        """Each target's position and rotation into its effector's row. A :class:`Target`'s position (3,) and
        rotation (3, 3) are float64 in C order: their bytes go straight into the rows' bytes (a quarter of NumPy's
        item assignment), at the places :meth:`_row_places` found for this layout."""
        cached = self._row_bytes
        if cached is None or cached[0] is not self._layout:
            cached = self._row_bytes = (self._layout, *self._row_places())
        _, rows, places = cached
        for t, (at_p, at_R) in zip(self._target_map.values(), places):  # no moves pending: a packing reads _targets
            if at_p is not None:
                rows[at_p] = t.position.tobytes()
                rows[at_R] = t.rotation.tobytes()

    def _row_places(self) -> tuple:
        """``(float buffer's bytes, (position's, rotation's byte slice) of each target in order)``, both ``None``
        for a target off the effectors: made again when the targets' layout or the buffers change."""
        rows = memoryview(self._buffers.floats).cast("B")
        p0, R0 = (8 * i for i in target_rows_at(self._buffers.sizes))
        places = []
        for name in self._targets:
            k = self._row_of.get(name)
            places.append((None, None) if k is None else (slice(p0 + 24 * k, p0 + 24 * k + 24),
                                                          slice(R0 + 72 * k, R0 + 72 * k + 72)))
        return rows, places

    def _make_fast_rows(self) -> dict:
        """``{target name: (compiled move_position_at, compiled move_pose_at, float buffer, position's index,
        rotation's index)}`` of the targets :meth:`move_target` writes straight into the kernels' rows (none on the
        prioritised path); made again after the targets' packing changes (``_fast_rows`` None)."""
        if self._is_controlled:
            self._fast_rows = {}
            return self._fast_rows
        floats = self._buffers.floats
        moves = self._moves or self._make_moves()
        p0, R0 = target_rows_at(self._buffers.sizes)
        self._fast_rows = {name: (*moves, floats, p0 + 3 * k, R0 + 9 * k)
                           for name in self._target_map if (k := self._row_of.get(name)) is not None}
        return self._fast_rows

    def _move_checked(self, name: str, position, orientation) -> None:
        """:meth:`move_target` for any input: checked as :class:`Target` checks it, or refused."""
        if name not in self._target_map:
            self._check_target_name(name)
            raise TargetError(f"{name!r} has no target to move; set one first (set_target or set_targets); "
                              f"targets: {choices(self._target_map) or 'none'}")
        try:
            xyz = checked_position(position)
            q, rows = (None, None) if orientation is None else checked_rotation(orientation)
        except TargetError as exc:
            raise TargetError(f"target for {name!r}: {exc}") from None
        k = self._row_of.get(name)
        if k is None or self._is_controlled:  # the prioritised path retargets its controller from the targets
            self._targets[name] = self._targets[name]._moved_to(xyz, q, rows)
            self._pack_targets()
            return
        # Straight into the packed rows' memory (C order, float64): cheaper than NumPy's item assignment.
        PACK3_INTO(self._packed.position, 24 * k, *xyz)
        if rows is not None:
            PACK9_INTO(self._packed.rotation, 72 * k, *rows)
        self._moved[name] = (q, True) if rows is not None else self._moved.get(name, (None, False))

    def _make_moves(self) -> tuple:
        """:func:`gsik.kernels.targets.move_position_at` and ``move_pose_at`` compiled for arrays of any layout (a
        transform's column is strided), kept."""
        floats = self._buffers.floats
        self._moves = (kernels.compiled_entry(move_position_at, _ANY_VECTOR, floats, 0),
                       kernels.compiled_entry(move_pose_at, _ANY_VECTOR, _ANY_MATRIX, floats, 0, 0))
        return self._moves

    def _check_targets(self, targets: Mapping[str, Target | None]) -> tuple[dict[str, Target], tuple]:
        """``(the enabled targets, their layout)``: the layout ``((name, weight, position_only, priority), ...)``
        in order, what :meth:`_pack_targets` compares to know that only the values moved."""
        if type(targets) is not dict and not isinstance(targets, Mapping):
            raise TargetError(f"targets must be a mapping of effector name to Target, got {type(targets).__name__}")
        out, layout, valid = {}, [], self._valid_names
        for name, t in targets.items():
            if name not in valid:
                self._check_target_name(name)
            if t is None:
                continue
            if type(t) is not Target and not isinstance(t, Target):
                raise TargetError(f"target for {name!r} must be a gsik.Target, got {type(t).__name__}")
            if t.enabled:  # a disabled target leaves its effector free, as no target does
                out[name] = t
                layout.append((name, t.weight, t.position_only, t.priority))
        if len(out) > MAX_PRIORITY_LEVELS:  # fewer targets cannot make too many levels
            _check_target_counts(out)
        return out, tuple(layout)

    def _check_target_name(self, name) -> None:
        """Raise :class:`TargetError` unless ``name`` is an effector, or a joint or site other than the root."""
        if name in self._topo.effector_names or (name != self.root and name in self._target_frames):
            return
        extra = f" ({name!r} is the IK root)" if name == self.root else ""
        others = [n for n in self.target_names if n not in self._topo.effector_names]
        raise TargetError(f"no effector {name!r}{extra}; effectors: {choices(self._topo.effector_names)}; "
                          f"other joints and sites: {choices(others)}")


def _check_target_counts(targets: Mapping[str, Target]) -> None:
    """At most :data:`MAX_TARGETS` enabled targets on at most :data:`MAX_PRIORITY_LEVELS` levels: a step's cost
    grows with both (a level is one least-squares solve in what the levels above leave)."""
    if len(targets) > MAX_TARGETS:
        raise TargetError(f"{len(targets):,} enabled targets; the limit is {MAX_TARGETS:,}")
    levels = {t.priority for t in targets.values()}
    if len(levels) > MAX_PRIORITY_LEVELS:
        raise TargetError(f"targets on {len(levels):,} priority levels; the limit is {MAX_PRIORITY_LEVELS} (give "
                          "targets that may trade off against each other the same priority)")
