"""The document of gsik-studio: skeleton, solver, targets, undo history, file.

Plain Python: no Qt, no PyVista. The window and the viewport draw a
:class:`Document` and forward input to it; tests drive it without a display.

Every edit is a command on the :class:`History`. A command keeps the
complete :class:`gsik.io.pose.Pose` from before the edit; when it is undone it
also keeps the pose from just before the undo, so undo and redo restore
angles, root and targets exactly, bit for bit (the solver keeps settling the
pose between edits, and redo gives back the settled pose, not a guess).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

import gsik
from gsik.errors import PoseError, choices
from gsik.anim.motion import Motion
from gsik.io.pose import Pose, PoseRead, read_pose, write_pose
from gsik.targets import Target
from gsik.rotations import matrix_from_axis_angle, matrix_from_quaternion, quaternion_from_matrix, transform

#: Axis names of the world, for rotating a target about one of them.
WORLD_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}

#: Solver settings the studio starts with (a frame's budget: a few sweeps).
DEFAULT_SETTINGS = dict(sweeps=8, damping=1e-3)


class Signal:
    """A minimal observer list: ``connect(fn)``, ``emit(*args)``."""

    def __init__(self):
        self._slots: list[Callable] = []

    def connect(self, slot: Callable) -> None:
        self._slots.append(slot)

    def disconnect(self, slot: Callable) -> None:
        self._slots.remove(slot)

    def emit(self, *args) -> None:
        for slot in list(self._slots):
            slot(*args)


@dataclass(eq=False)
class Command:
    """One undoable edit.

    Attributes:
        text: What the edit did, for menus ("Move left_hand").
        before: The document's pose before the edit.
        after: The pose to restore on redo; set when the command is undone.
        merge_key: Consecutive commands with the same non-None key merge
            into one (every mouse move of one drag is one command).
    """

    text: str
    before: Pose
    after: Pose | None = None
    merge_key: object | None = None


@dataclass(eq=False)
class History:
    """An undo stack: ``commands[:index]`` are done, the rest undone (redoable)."""

    limit: int = 500
    commands: list[Command] = field(default_factory=list)
    index: int = 0
    clean_index: int | None = 0

    @property
    def can_undo(self) -> bool:
        return self.index > 0

    @property
    def can_redo(self) -> bool:
        return self.index < len(self.commands)

    @property
    def undo_text(self) -> str:
        return self.commands[self.index - 1].text if self.can_undo else ""

    @property
    def redo_text(self) -> str:
        return self.commands[self.index].text if self.can_redo else ""

    @property
    def is_clean(self) -> bool:
        return self.index == self.clean_index

    def push(self, command: Command) -> bool:
        """Add a done command; returns False when it merged into the previous one."""
        del self.commands[self.index:]
        if self.clean_index is not None and self.clean_index > self.index:
            self.clean_index = None  # the saved state can no longer be reached
        top = self.commands[-1] if self.commands else None
        if top is not None and command.merge_key is not None and top.merge_key == command.merge_key:
            if self.clean_index == self.index:
                self.clean_index = None
            return False
        self.commands.append(command)
        if len(self.commands) > self.limit:
            del self.commands[0]
            self.clean_index = None if self.clean_index in (None, 0) else self.clean_index - 1
        self.index = len(self.commands)
        return True

    def would_merge(self, merge_key: object | None) -> bool:
        """True if a command with ``merge_key`` would merge into the current top."""
        return (merge_key is not None and self.index == len(self.commands) and bool(self.commands)
                and self.commands[-1].merge_key == merge_key)

    def end_merge(self) -> None:
        """The next command does not merge into the current top (a drag ended)."""
        if self.commands:
            self.commands[-1].merge_key = None

    def set_clean(self) -> None:
        self.clean_index = self.index

    def clear(self) -> None:
        self.commands.clear()
        self.index = 0
        self.clean_index = 0


def mirror_map(skeleton: gsik.Skeleton, source: str) -> list[tuple[int, int, float]]:
    """``(from_dof, to_dof, sign)`` copying the ``source`` side's angles to the other side.

    The two sides are mirror images in the plane x = 0 (the biped's sagittal
    plane). Reflecting a rotation about axis ``a`` gives the rotation about
    ``-M a`` by the same angle (``M`` = diag(-1, 1, 1)), so a pitch (x) keeps
    its sign and a roll (y) or twist (z) changes it. DOFs whose counterpart
    has an axis that is not the mirror image are skipped.
    """
    if source not in ("left", "right"):
        raise ValueError(f"mirror source must be 'left' or 'right', got {source!r}")
    other = "right" if source == "left" else "left"
    M = np.diag([-1.0, 1.0, 1.0])
    out = []
    for i, name in enumerate(skeleton.dof_names):
        if not name.startswith(source + "_"):
            continue
        twin = other + name[len(source):]
        if twin not in skeleton.dof_names:
            continue
        j = skeleton.dof_names.index(twin)
        a = -M @ skeleton.frame_axis[skeleton.dof_frame[i]]
        b = skeleton.frame_axis[skeleton.dof_frame[j]]
        d = float(a @ b)
        if abs(abs(d) - 1.0) < 1e-6:
            out.append((i, j, 1.0 if d > 0 else -1.0))
    return out


class Document:
    """One open pose: the skeleton, its solver, targets, undo history and file.

    Args:
        skeleton: A :class:`gsik.Skeleton` or the name of a bundled one.
        settings: Solver settings overriding :data:`DEFAULT_SETTINGS`.

    Signals (plain callbacks, see :class:`Signal`):
        changed(kind): ``"pose"`` (angles, root or targets replaced),
            ``"targets"`` (a target moved or turned), ``"options"`` (a target's
            enabled / weight / position-only changed), ``"settings"``, ``"file"``
            (path or dirty flag), ``"history"``.
    """

    #: Effectors whose targets start position-only: the biped's arms have no
    #: wrist, so a full 6-DOF hand target would fight the rest of the body.
    POSITION_ONLY_BY_DEFAULT = ("left_hand", "right_hand")

    def __init__(self, skeleton: gsik.Skeleton | str = "biped", **settings):
        self.skeleton = gsik.load_skeleton(skeleton) if isinstance(skeleton, str) else skeleton
        self.solver = gsik.Solver(self.skeleton, **{**DEFAULT_SETTINGS, **settings})
        self.history = History()
        self.path: str | None = None
        self.changed = Signal()
        self.last_result: gsik.SolveResult | None = None
        self.last_solve_time = 0.0  # [s]
        self.needs_solving = True
        self._targets: dict[str, Target] = {}
        self._playback: Playback | None = None
        self._root_position = (0.0, 0.0, 0.0)
        self._root_orientation = (1.0, 0.0, 0.0, 0.0)
        self._initial = self._standing_pose({})
        self._restore(self._initial)
        self._mirror = {s: mirror_map(self.skeleton, s) for s in ("left", "right")}

    # -- state -----------------------------------------------------------------
    @property
    def root(self) -> str:
        return self.solver.root

    @property
    def effector_names(self) -> tuple[str, ...]:
        """Effectors of the current root (every effector site but the root)."""
        return self.solver.effector_names

    @property
    def targets(self) -> dict[str, Target]:
        """``{effector: Target}`` (a new dict; the targets are immutable)."""
        return dict(self._targets)

    @property
    def q(self) -> np.ndarray:
        return self.solver.q

    @property
    def dirty(self) -> bool:
        """True when the document has changes not saved to :attr:`path`."""
        return not self.history.is_clean

    @property
    def title(self) -> str:
        return os.path.basename(self.path) if self.path else "Untitled"

    def pose(self) -> Pose:
        """A complete snapshot of the document (what a pose file holds)."""
        q = self.solver.q
        return Pose(self.skeleton.name, self.solver.root, self._root_position, self._root_orientation,
                    dict(zip(self.skeleton.dof_names, q.tolist())), self._targets)

    def effector_poses(self) -> dict[str, np.ndarray]:
        """``{effector: world transform (4, 4)}`` as achieved now."""
        return self.solver.effector_poses()

    def limit_mask(self, tolerance: float = 1e-4) -> np.ndarray:
        """(n_dofs,) True where an angle sits on a limit (within ``tolerance`` [rad])."""
        q = self.solver.q
        sk = self.skeleton
        return ((q <= sk.lower + tolerance) | (q >= sk.upper - tolerance)) & (sk.upper > sk.lower)

    # -- applying state ----------------------------------------------------------
    def _standing_pose(self, flags: Mapping[str, Target]) -> Pose:
        """The skeleton's rest pose on its default root, targets on the effectors."""
        sk = self.skeleton
        solver = gsik.Solver(sk)
        W = solver.world_from_root
        targets = {}
        for name, T in solver.effector_poses().items():
            old = flags.get(name)
            targets[name] = Target.from_transform(
                T, enabled=True if old is None else old.enabled, weight=1.0 if old is None else old.weight,
                position_only=(name in self.POSITION_ONLY_BY_DEFAULT) if old is None else old.position_only)
        return Pose(sk.name, sk.root, tuple(W[:3, 3]), tuple(quaternion_from_matrix(W[:3, :3])),
                    dict(zip(sk.dof_names, sk.rest.tolist())), targets)

    def _check_pose(self, pose: Pose) -> None:
        sk = self.skeleton
        if pose.skeleton != sk.name:
            raise PoseError(f"pose is for skeleton {pose.skeleton!r}, this document's is {sk.name!r}")
        sk.frame_of(pose.root)
        missing = [n for n in sk.dof_names if n not in pose.joints]
        if missing:
            raise PoseError(f"pose has no angle for {choices(missing)}")
        effectors = [n for n in sk.effector_sites if n != pose.root]
        if set(pose.targets) != set(effectors):
            raise PoseError(f"pose targets {choices(pose.targets)} do not match the effectors {choices(effectors)}")

    def _restore(self, pose: Pose) -> None:
        """Make the document show ``pose`` exactly (no command)."""
        self._check_pose(pose)
        q = np.clip(pose.q(self.skeleton), self.skeleton.lower, self.skeleton.upper)
        if pose.root != self.solver.root:
            self.solver.set_root(pose.root)
        self._root_position = pose.root_position
        self._root_orientation = pose.root_orientation
        self.solver.set_world_from_root(pose.world_from_root)
        self.solver.set_q(q)
        self._targets = {n: pose.targets[n] for n in self.solver.effector_names}
        self._push_targets()
        self.needs_solving = True
        self.last_result = None

    def _push_targets(self) -> None:
        """Hand the targets to the solver (it skips the disabled ones)."""
        self.solver.set_targets(self._targets)
        self.needs_solving = True

    def _snapped_targets(self) -> dict[str, Target]:
        """Targets moved onto the achieved effector poses, flags kept."""
        out = {}
        for n, T in self.solver.effector_poses().items():
            old = self._targets.get(n)
            out[n] = Target.from_transform(T) if old is None else Target.from_transform(
                T, old.weight, old.position_only, old.enabled)
        return out

    # -- commands --------------------------------------------------------------
    def _interrupt_playback(self) -> None:
        """An edit, undo, redo or load ends a running playback first (recorded as its own undo step)."""
        pb = self._playback
        if pb is not None and not pb.finished and not pb.applying:
            pb.stop()

    def _edit(self, text: str, apply: Callable[[], None], merge_key: object | None = None,
              kind: str = "pose") -> None:
        self._interrupt_playback()
        merging = self.history.would_merge(merge_key)
        before = None if merging else self.pose()  # a merged move keeps the drag's first "before"
        apply()
        self.needs_solving = True
        if merging:
            self.history.push(Command(text, self.history.commands[-1].before, merge_key=merge_key))
        else:
            self.history.push(Command(text, before, merge_key=merge_key))
        self.changed.emit(kind)
        if not merging:
            self.changed.emit("history")
        self.changed.emit("file")

    def _effector(self, name: str) -> Target:
        try:
            return self._targets[name]
        except KeyError:
            why = " (it is the IK root)" if name == self.root else ""
            raise gsik.TargetError(f"no effector {name!r}{why}; effectors: {choices(self._targets)}") from None

    def set_target(self, name: str, target: Target, text: str | None = None,
                   merge_key: object | None = None) -> None:
        """Replace one effector's target (the general form of every target edit).

        Emits ``changed("targets")`` when only the position or orientation
        changed, ``changed("options")`` when enabled, weight or position-only did.
        """
        self._effector(name)
        if not isinstance(target, Target):
            raise gsik.TargetError(f"target for {name!r} must be a gsik.Target, got {type(target).__name__}")

        old = self._targets[name]
        same_flags = (old.enabled, old.weight, old.position_only) == (target.enabled, target.weight,
                                                                      target.position_only)

        def apply():
            self._targets[name] = target
            self._push_targets()

        self._edit(text or f"Edit {name} target", apply, merge_key, kind="targets" if same_flags else "options")

    def move_targets(self, positions: Mapping[str, Sequence[float]], drag: object | None = None) -> None:
        """Move several targets at once (one undo step; merged over one ``drag`` token)."""
        new = {n: self._effector(n).replace(position=p) for n, p in positions.items()}

        def apply():
            self._targets.update(new)
            self._push_targets()

        key = None if drag is None else ("move", tuple(sorted(new)), drag)
        self._edit(f"Move {', '.join(new)}", apply, key, kind="targets")

    def move_target(self, name: str, position, drag: object | None = None) -> None:
        """Move a target to a world position (3,) [m].

        Every move with the same ``drag`` token (one mouse drag) merges
        into one undo step; ``None`` makes a step of its own.
        """
        t = self._effector(name).replace(position=position)
        self.set_target(name, t, f"Move {name}", None if drag is None else ("move", name, drag))

    def end_drag(self) -> None:
        """A mouse drag ended: the next move is a new undo step."""
        self.history.end_merge()

    def orient_target(self, name: str, orientation, drag: object | None = None) -> None:
        """Set a target's world orientation: quaternion (w, x, y, z) or matrix (3, 3)."""
        t = self._effector(name).replace(orientation=orientation)  # a matrix is kept as the rotation
        self.set_target(name, t, f"Rotate {name}", None if drag is None else ("rotate", name, drag))

    def rotate_target(self, name: str, axis: str, angle: float) -> None:
        """Turn a target by ``angle`` [rad] about the world ``axis`` ("x", "y" or "z") through its centre."""
        if axis not in WORLD_AXES:
            raise ValueError(f"axis must be one of {choices(WORLD_AXES)}, got {axis!r}")
        t = self._effector(name)
        R = matrix_from_axis_angle(np.array(WORLD_AXES[axis]), angle) @ t.rotation
        self.set_target(name, t.replace(orientation=R),
                        f"Rotate {name} about {axis}")

    def set_target_options(self, name: str, *, enabled: bool | None = None, weight: float | None = None,
                           position_only: bool | None = None) -> None:
        """Enable or disable an effector, change its weight or its position-only flag."""
        t = self._effector(name)
        changes = {k: v for k, v in dict(enabled=enabled, weight=weight, position_only=position_only).items()
                   if v is not None}
        new = t.replace(**changes)
        if new == t:
            return
        what = ", ".join(f"{k} {v}" for k, v in changes.items())
        self.set_target(name, new, f"Set {name} {what}")

    def snap_target(self, name: str) -> None:
        """Move one target onto its effector's achieved pose."""
        t = self._effector(name)
        T = self.solver.effector_poses()[name]
        self.set_target(name, Target.from_transform(T, t.weight, t.position_only, t.enabled), f"Snap {name}")

    def set_root(self, name: str) -> None:
        """Pin another joint or site (usually the other foot); no joint moves.

        The old root, if it is an effector site, gets a target where it
        stands; the new root's target is dropped.
        """
        self.skeleton.frame_of(name)
        if name == self.root:
            return

        def apply():
            old = self.solver.root
            self.solver.set_root(name)
            W = self.solver.world_from_root
            self._root_position = tuple(W[:3, 3])
            self._root_orientation = tuple(quaternion_from_matrix(W[:3, :3]))
            self.solver.set_world_from_root(self.pose().world_from_root)
            new = {n: t for n, t in self._targets.items() if n != name}
            if old in self.solver.effector_names:
                new[old] = Target.from_transform(self.solver.effector_poses()[old])
            self._targets = {n: new[n] for n in self.solver.effector_names}
            self._push_targets()

        self._edit(f"Root on {name}", apply)

    def set_pose(self, pose: Pose, text: str = "Set pose") -> None:
        """Replace the whole pose (angles, root, targets) as one undo step."""
        self._check_pose(pose)
        self._edit(text, lambda: self._restore(pose))

    def set_angles(self, q, text: str = "Set angles", snap_targets: bool = True) -> None:
        """New joint angles (n_dofs,) [rad] (clamped into the limits), the root staying pinned.

        With ``snap_targets`` the targets move onto the new effector poses,
        so the pose holds.
        """
        q = np.clip(self.skeleton.validate_q(q), self.skeleton.lower, self.skeleton.upper)

        def apply():
            self.solver.set_q(q)
            if snap_targets:
                self._targets = self._snapped_targets()
            self._push_targets()

        self._edit(text, apply)

    def reset(self) -> None:
        """Back to the standing pose on the default root; effector flags are kept."""
        self.set_pose(self._standing_pose(self._targets), "Reset to standing pose")

    def random_pose(self, seed: int | None = None, amount: float = 0.35) -> None:
        """A random pose: every angle moved from rest by up to ``amount`` of the way to its limits."""
        rng = np.random.default_rng(seed)
        sk = self.skeleton
        u = rng.uniform(-1.0, 1.0, sk.n_dofs)
        span = np.where(u < 0, sk.rest - sk.lower, sk.upper - sk.rest)
        self.set_angles(sk.rest + amount * u * span, "Random pose")

    def mirror(self, source: str) -> None:
        """Copy the ``source`` side's angles ("left" or "right") mirrored onto the other side."""
        if source not in self._mirror:
            raise ValueError(f"mirror source must be 'left' or 'right', got {source!r}")
        q = self.solver.q
        for i, j, sign in self._mirror[source]:
            q[j] = sign * q[i]
        other = "right" if source == "left" else "left"
        self.set_angles(q, f"Mirror {source} to {other}")

    def undo(self) -> bool:
        """Undo the last edit exactly; False when there is none."""
        self._interrupt_playback()
        if not self.history.can_undo:
            return False
        cmd = self.history.commands[self.history.index - 1]
        cmd.after = self.pose()
        cmd.merge_key = None
        self._restore(cmd.before)
        self.history.index -= 1
        self._emit_all()
        return True

    def redo(self) -> bool:
        """Redo the last undone edit exactly; False when there is none."""
        self._interrupt_playback()
        if not self.history.can_redo:
            return False
        cmd = self.history.commands[self.history.index]
        self._restore(cmd.after)
        self.history.index += 1
        self._emit_all()
        return True

    def _emit_all(self) -> None:
        for kind in ("pose", "history", "file"):
            self.changed.emit(kind)

    # -- solver ----------------------------------------------------------------
    def step(self) -> gsik.SolveResult:
        """One solver frame; afterwards :attr:`needs_solving` says whether more frames would help."""
        t0 = time.perf_counter()
        result = self.solver.step()
        self.last_solve_time = time.perf_counter() - t0
        self.last_result = result
        self.needs_solving = result.status is gsik.Status.BUDGET_EXHAUSTED
        return result

    @property
    def settings(self) -> gsik.SolverSettings:
        return self.solver.settings

    def configure(self, **changes) -> None:
        """Change solver settings (validated by gsik; :class:`gsik.SolverError` on a bad value)."""
        self.solver.configure(**changes)
        self.needs_solving = True
        self.changed.emit("settings")

    # -- files -----------------------------------------------------------------
    def open(self, path: str) -> tuple[str, ...]:
        """Load a pose file; returns its warnings (angles clamped into limits).

        On any error (:class:`gsik.GsikFileError`, :class:`gsik.PoseError`)
        the document is left exactly as it was.
        """
        read: PoseRead = read_pose(path, self.skeleton)
        self._interrupt_playback()
        self._restore(read.pose)
        self.history.clear()
        self.path = str(path)
        if read.warnings:
            self.history.clean_index = None  # what is shown differs from the file
        self._emit_all()
        return read.warnings

    def save(self, path: str | None = None) -> None:
        """Write the pose atomically to ``path`` (default: the current file).

        Raises:
            GsikFileError: nothing was written; the document keeps its path and dirty flag.
        """
        target = path or self.path
        if not target:
            raise gsik.GsikFileError("no file name to save to (use Save As)")
        write_pose(target, self.pose())
        self.path = str(target)
        self.history.set_clean()
        self.changed.emit("file")

    def new(self) -> None:
        """The standing pose, no file, empty history."""
        self._interrupt_playback()
        self._restore(self._standing_pose({}))
        self.history.clear()
        self.path = None
        self._emit_all()

    # -- playback (hook for walks and scenarios) -------------------------------
    def playback(self, frames: Motion | Sequence[Mapping[str, Target | None]],
                 text: str = "Play", frame_time: float = 1 / 30) -> Playback:
        """A :class:`Playback` of a :class:`gsik.anim.motion.Motion` or of a sequence of target dicts.

        A playback running already is stopped first. Any edit, undo, redo or
        load while it runs stops it (what was played so far stays, as one step).
        """
        self._interrupt_playback()
        pb = Playback(self, frames, text, frame_time)
        self._playback = pb
        return pb


class Playback:
    """Plays frames onto a document, then records the result as one undo step.

    A frame is either a frame of a :class:`gsik.anim.motion.Motion` (angles, root
    and root transform applied directly) or a dict of targets (applied, then
    the solver steps). Call :meth:`advance` once per frame (the window does it
    from a timer every :attr:`frame_time` seconds) until it returns False,
    or :meth:`stop` to end early; the played result is then one command
    (``text``) that undo takes back to the pose before playing.
    """

    def __init__(self, doc: Document, frames, text: str, frame_time: float):
        self.doc = doc
        self.text = text
        if isinstance(frames, Motion):
            if frames.skeleton.name != doc.skeleton.name:
                raise gsik.GsikError(f"motion is for skeleton {frames.skeleton.name!r}, not {doc.skeleton.name!r}")
            self.motion: Motion | None = frames
            self.target_frames: Sequence = ()
            self.n_frames = frames.n_frames
            self.frame_time = float(frames.frame_time)
        else:
            self.motion = None
            self.target_frames = list(frames)
            self.n_frames = len(self.target_frames)
            self.frame_time = float(frame_time)
        self.index = 0
        self.before = doc.pose()
        self.finished = False
        self.applying = False

    def advance(self) -> bool:
        """Show the next frame; False when there is none (the playback then finishes)."""
        if self.finished:
            return False
        if self.index >= self.n_frames:
            self.stop()
            return False
        doc = self.doc
        self.applying = True
        try:
            self._apply(doc)
        finally:
            self.applying = False
        self.index += 1
        doc.changed.emit("pose")
        return True

    def _apply(self, doc: Document) -> None:
        if self.motion is not None:
            m = self.motion
            root = m.roots[self.index]
            if root != doc.solver.root:
                doc.solver.set_root(root)
            W = m.world_from_root[self.index]
            doc._root_position = tuple(W[:3, 3])
            doc._root_orientation = tuple(quaternion_from_matrix(W[:3, :3]))
            doc.solver.set_world_from_root(transform(matrix_from_quaternion(np.array(doc._root_orientation)),
                                                     W[:3, 3]))
            doc.solver.set_q(np.clip(m.q[self.index], doc.skeleton.lower, doc.skeleton.upper))
            doc._targets = doc._snapped_targets()
            doc._push_targets()
            doc.needs_solving = False
        else:
            frame = self.target_frames[self.index]
            for name, t in frame.items():
                old = doc._targets.get(name)
                if old is None:  # not an effector of the current root (the root itself): nothing to drive
                    continue
                if t is None:
                    doc._targets[name] = old.replace(enabled=False)
                elif t.position_only:  # no orientation asked for: keep the one shown
                    doc._targets[name] = old.replace(position=t.position, weight=t.weight, position_only=True,
                                                     enabled=t.enabled)
                else:
                    doc._targets[name] = t
            doc._push_targets()
            doc.step()

    def stop(self) -> None:
        """End the playback here and record it as one undo step."""
        if self.finished:
            return
        self.finished = True
        if self.doc._playback is self:
            self.doc._playback = None
        self.doc.history.push(Command(self.text, self.before))
        self.doc.needs_solving = True
        self.doc._emit_all()
