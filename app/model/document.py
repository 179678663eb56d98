"""The document of gsik-studio: skeleton, solver, targets, undo history, file.

Plain Python: no Qt, no PyVista. The :class:`Document` is the app's only door to the solver: the window and the
viewport read typed read-outs from it (:meth:`Document.world_positions`, :attr:`Document.targets`, ...) and forward
input to its commands; it says what changed through :attr:`Document.events`.

Every edit is a command on the :class:`History`. A command keeps the complete :class:`gsik.io.pose.Pose` from
before the edit; when it is undone it also keeps the pose from just before the undo, so undo and redo restore
angles, root and targets exactly, bit for bit (the solver keeps settling the pose between edits, and redo gives
back the settled pose, not a guess).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

import gsik
from gsik.errors import choices
from gsik.anim.motion import Motion
from gsik.anim.scenario_run import QUIET_FRAMES, SETTLED
from gsik.io.pose import Pose, PoseRead, read_pose, write_pose
from gsik.targets import Target
from gsik.rotations import matrix_from_axis_angle
from gsik_studio.model.events import DocumentEvents, Signal
from gsik_studio.model.history import Command, History
from gsik_studio.model.kept import Kept, file_fields, kept_from_file, kept_state, show_kept
from gsik_studio.model.library import PoseLibrary
from gsik_studio.model.mirror import mirror_map
from gsik_studio.model.pins import SolveControls, default_levels
from gsik_studio.model.poses import RootPlacement, check_pose, driven_target, standing_pose, target_at
from gsik_studio.model.timeline import Timeline
from gsik_studio.model.words import names_words, words

if TYPE_CHECKING:
    from gsik_studio.model.playback import Playback

#: Axis names of the world, for rotating a target about one of them.
WORLD_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}

#: Solver settings the studio starts with (a frame's budget: a few sweeps).
DEFAULT_SETTINGS = dict(sweeps=8, damping=1e-3, tracking_steps=3)  # a dragged target keeps up (gsik.control)


class Document:
    """One open pose: the skeleton, its solver, targets, undo history and file.

    Args:
        skeleton: A :class:`gsik.Skeleton` or the name of a bundled one.
        settings: Solver settings overriding :data:`DEFAULT_SETTINGS`.

    Attributes:
        events: What changed (see :class:`gsik_studio.model.events.DocumentEvents`).
        last_result: The last solver step's result (None after the pose was replaced).
        last_solve_time: How long the last solver step took [s].
        needs_solving: True until a step converges or QUIET_FRAMES steps in a row settle (as ``gsik scenarios``).
    """

    #: Effectors whose targets start position-only (without wrists, as the biped's, a turned hand turns the body).
    POSITION_ONLY_BY_DEFAULT = ("left_hand", "right_hand")

    def __init__(self, skeleton: gsik.Skeleton | str = "biped", **settings):
        self.skeleton = gsik.load_skeleton(skeleton) if isinstance(skeleton, str) else skeleton
        self.solver = gsik.Solver(self.skeleton, **{**DEFAULT_SETTINGS, **settings})
        self.history = History()
        self.path: str | None = None
        self.events = DocumentEvents()
        self.last_result: gsik.SolveResult | None = None
        self.last_solve_time = 0.0  # [s]
        self.needs_solving = True
        self._targets: dict[str, Target] = {}
        self._playback: Playback | None = None
        self._placement = RootPlacement((0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))
        self.controls = SolveControls(self.solver, self._push_targets, self._edit)
        self._restore(standing_pose(self.skeleton, {}, self.POSITION_ONLY_BY_DEFAULT, default_levels(self.skeleton)))
        self._mirror = {s: mirror_map(self.skeleton, s) for s in ("left", "right")}
        self.timeline = Timeline(self)  # the motion kept with the pose
        self.library = PoseLibrary(self)  # named poses, undone with the pose

    # -- read-outs -------------------------------------------------------------
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

    @property
    def settings(self) -> gsik.SolverSettings:
        return self.solver.settings

    def pose(self) -> Pose:
        """A complete snapshot of the document (what a pose file holds)."""
        p = self._placement
        return Pose(self.skeleton.name, self.solver.root, p.root_position, p.root_orientation,
                    dict(zip(self.skeleton.dof_names, self.solver.q.tolist())), self._targets)

    def world_positions(self) -> np.ndarray:
        """World positions (n_frames, 3) [m] of every skeleton frame (a copy)."""
        return self.solver.world_positions()

    def world_rotations(self) -> np.ndarray:
        """World rotations (n_frames, 3, 3) of every skeleton frame (a copy)."""
        return self.solver.world_rotations()

    def effector_poses(self) -> dict[str, np.ndarray]:
        """``{effector: world transform (4, 4)}`` as achieved now."""
        return self.solver.effector_poses()

    def effector_errors(self) -> dict[str, tuple[float, float]]:
        """``{effector: (position error [m], orientation error [rad])}`` of the last solver step ({} if none)."""
        return self.last_result.errors() if self.last_result is not None else {}

    def limit_mask(self, tolerance: float = 1e-4) -> np.ndarray:
        """(n_dofs,) True where an angle sits on a limit (within ``tolerance`` [rad])."""
        q = self.solver.q
        sk = self.skeleton
        return ((q <= sk.lower + tolerance) | (q >= sk.upper - tolerance)) & (sk.upper > sk.lower)

    # -- applying state ----------------------------------------------------------
    def _place_root(self, root: str, placement: RootPlacement) -> None:
        """Pin ``root`` at ``placement``: the one place the root's placement is set."""
        if root != self.solver.root:
            self.solver.set_root(root)
        self._placement = placement
        self.solver.set_world_from_root(placement.world_from_root)

    def _restore(self, pose: Pose) -> None:
        """Make the document show ``pose`` exactly (no command)."""
        check_pose(self.skeleton, pose)
        q = np.clip(pose.q(self.skeleton), self.skeleton.lower, self.skeleton.upper)
        self._place_root(pose.root, RootPlacement(pose.root_position, pose.root_orientation))
        self.solver.set_q(q)
        self._targets = {n: pose.targets[n] for n in self.solver.effector_names}
        self._push_targets()
        self.last_result = None

    def _push_targets(self) -> None:
        """Hand the targets and the poles' aims to the solver (it skips the disabled ones)."""
        self.solver.set_targets({**self._targets, **self.controls.pole_aims()})
        self.needs_solving = True

    def _snapped_targets(self) -> dict[str, Target]:
        """Targets moved onto the achieved effector poses, flags kept."""
        return {n: target_at(T, self._targets.get(n)) for n, T in self.solver.effector_poses().items()}

    # -- commands --------------------------------------------------------------
    def _interrupt_playback(self) -> None:
        """An edit, undo, redo or load ends a running playback first (recorded as its own undo step)."""
        if self._playback is not None:
            self._playback.stop()

    def _file_state(self) -> tuple[str | None, bool]:
        return self.path, self.dirty

    def _emit_file(self, before: tuple[str | None, bool]) -> None:
        """``events.file`` when the path or the unsaved-changes flag differs from ``before``."""
        if self._file_state() != before:
            self.events.file.emit()

    def _edit(self, text: str, apply: Callable[[], None], merge_key: object | None = None,
              signal: Signal | None = None) -> None:
        """Run ``apply`` as one undo step (merged into the last one with the same ``merge_key``)."""
        self._interrupt_playback()
        merging = self.history.would_merge(merge_key)
        before = self.history.commands[-1].before if merging else self.pose()  # a drag keeps its first "before"
        file_state = self._file_state()
        kept = kept_state(self)
        apply()
        self.needs_solving = True
        self.history.push(Command(text, before, merge_key=merge_key, kept_before=kept))
        (signal or self.events.pose).emit()
        if not merging:
            self.events.history.emit()
        self._emit_file(file_state)

    def _replaced(self, file_state: tuple[str | None, bool]) -> None:
        """The whole pose and the history changed (undo, redo, open, new, a playback recorded)."""
        self.events.pose.emit()
        self.events.history.emit()
        self._emit_file(file_state)

    def _effector(self, name: str) -> Target:
        try:
            return self._targets[name]
        except KeyError:
            why = " (it is the IK root)" if name == self.root else ""
            raise gsik.TargetError(f"no effector {name!r}{why}; effectors: {choices(self._targets)}") from None

    def set_target(self, name: str, target: Target, text: str | None = None,
                   merge_key: object | None = None) -> None:
        """Replace one effector's target (the general form of every target edit).

        Emits ``events.targets`` when only the position or orientation
        changed, ``events.options`` when enabled, weight or position-only did.
        """
        self._effector(name)
        if not isinstance(target, Target):
            raise gsik.TargetError(f"target for {name!r} must be a gsik.Target, got {type(target).__name__}")
        old = self._targets[name]
        same_flags = (old.enabled, old.weight, old.position_only, old.priority) == (
            target.enabled, target.weight, target.position_only, target.priority)

        def apply():
            self._targets[name] = target
            self._push_targets()

        signal = self.events.targets if same_flags else self.events.options
        self._edit(text or f"Edit {words(name)} target", apply, merge_key, signal)

    def move_targets(self, positions: Mapping[str, Sequence[float]], drag: object | None = None) -> None:
        """Move several targets at once (one undo step; merged over one ``drag`` token)."""
        new = {n: self._effector(n).replace(position=p) for n, p in positions.items()}

        def apply():
            self._targets.update(new)
            self._push_targets()

        key = None if drag is None else ("move", tuple(sorted(new)), drag)
        self._edit(f"Move {names_words(new)}", apply, key, self.events.targets)

    def move_target(self, name: str, position, drag: object | None = None) -> None:
        """Move a target to a world position (3,) [m].

        Every move with the same ``drag`` token (one mouse drag) merges
        into one undo step; ``None`` makes a step of its own.
        """
        t = self._effector(name).replace(position=position)
        self.set_target(name, t, f"Move {words(name)}", None if drag is None else ("move", name, drag))

    def end_drag(self) -> None:
        """A mouse drag ended: the next move is a new undo step."""
        self.history.end_merge()

    def orient_target(self, name: str, orientation, drag: object | None = None) -> None:
        """Set a target's world orientation: quaternion (w, x, y, z) or matrix (3, 3)."""
        t = self._effector(name).replace(orientation=orientation)  # a matrix is kept as the rotation
        self.set_target(name, t, f"Rotate {words(name)}", None if drag is None else ("rotate", name, drag))

    def rotate_target(self, name: str, axis: str, angle: float) -> None:
        """Turn a target by ``angle`` [rad] about the world ``axis`` ("x", "y" or "z") through its centre."""
        if axis not in WORLD_AXES:
            raise ValueError(f"axis must be one of {choices(WORLD_AXES)}, got {axis!r}")
        t = self._effector(name)
        R = matrix_from_axis_angle(np.array(WORLD_AXES[axis]), angle) @ t.rotation
        self.set_target(name, t.replace(orientation=R), f"Rotate {words(name)} about {axis}")

    def set_target_options(self, name: str, *, enabled: bool | None = None, weight: float | None = None,
                           position_only: bool | None = None, priority: int | None = None) -> None:
        """Enable or disable an effector, change its weight, position-only flag or priority level (its pin)."""
        t = self._effector(name)
        changes = {k: v for k, v in dict(enabled=enabled, weight=weight, position_only=position_only,
                                         priority=priority).items() if v is not None}
        new = t.replace(**changes)
        if new == t:
            return
        what = ", ".join(f"{k} {v}" for k, v in changes.items())
        self.set_target(name, new, f"Set {words(name)} {what}")

    def snap_target(self, name: str) -> None:
        """Move one target onto its effector's achieved pose."""
        t = self._effector(name)
        self.set_target(name, target_at(self.solver.effector_poses()[name], t), f"Snap {words(name)}")

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
            self._place_root(name, RootPlacement.from_transform(self.solver.world_from_root))
            new = {n: t for n, t in self._targets.items() if n != name}
            if old in self.solver.effector_names:
                new[old] = target_at(self.solver.effector_poses()[old])
            self._targets = {n: new[n] for n in self.solver.effector_names}
            self._push_targets()

        self._edit(f"Root on {words(name)}", apply)

    def set_pose(self, pose: Pose, text: str = "Set pose") -> None:
        """Replace the whole pose (angles, root, targets) as one undo step."""
        check_pose(self.skeleton, pose)
        self._edit(text, lambda: self._restore(pose))

    def set_angles(self, q, text: str = "Set angles", snap_targets: bool = True, drag: object | None = None) -> None:
        """New joint angles (n_dofs,) [rad] (clamped into the limits), the root staying pinned.

        With ``snap_targets`` the targets move onto the new effector poses,
        so the pose holds. Calls with one ``drag`` token merge into one undo step.
        """
        q = np.clip(self.skeleton.validate_q(q), self.skeleton.lower, self.skeleton.upper)

        def apply():
            self.solver.set_q(q)
            if snap_targets:
                self._targets = self._snapped_targets()
            self._push_targets()

        self._edit(text, apply, None if drag is None else ("angles", text, drag))

    def reset(self) -> None:
        """Back to the standing pose on the default root, poles at their rest places; effector flags are kept."""
        pose = standing_pose(self.skeleton, self._targets, self.POSITION_ONLY_BY_DEFAULT)
        self._edit("Reset to standing pose", lambda: (self._restore(pose), self.controls.poles_to_rest()))

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
        file_state = self._file_state()
        cmd = self.history.commands[self.history.index - 1]
        cmd.after, cmd.kept_after = self.pose(), kept_state(self)
        cmd.merge_key = None
        self._restore(cmd.before)
        show_kept(self, cmd.kept_before)
        self.history.index -= 1
        self._replaced(file_state)
        return True

    def redo(self) -> bool:
        """Redo the last undone edit exactly; False when there is none."""
        self._interrupt_playback()
        if not self.history.can_redo:
            return False
        file_state = self._file_state()
        cmd = self.history.commands[self.history.index]
        self._restore(cmd.after)
        show_kept(self, cmd.kept_after)
        self.history.index += 1
        self._replaced(file_state)
        return True

    # -- solver ----------------------------------------------------------------
    def step(self) -> gsik.SolveResult:
        """One solver frame; afterwards :attr:`needs_solving` says whether more frames would help."""
        self.controls.aim_poles()  # the limbs' ends moved: the poles aim anew
        t0 = time.perf_counter()
        result = self.solver.step()
        self.last_solve_time = time.perf_counter() - t0
        self.last_result = result
        settled = self._quiet + 1 if result.status in SETTLED else 0
        self._quiet = QUIET_FRAMES if result.status is gsik.Status.CONVERGED else settled
        return result

    needs_solving = property(lambda self: self._quiet < QUIET_FRAMES,
                             lambda self, needed: setattr(self, "_quiet", 0 if needed else QUIET_FRAMES))

    def configure(self, **changes) -> None:
        """Change solver settings (validated by gsik; :class:`gsik.SolverError` on a bad value)."""
        self.solver.configure(**changes)
        self.needs_solving = True
        self.events.settings.emit()

    # -- files -----------------------------------------------------------------
    def open(self, path: str) -> tuple[str, ...]:
        """Load a pose file; returns its warnings (angles clamped into limits).

        On any error (:class:`gsik.GsikFileError`, :class:`gsik.PoseError`) the document is left exactly as it was.
        """
        read: PoseRead = read_pose(path, self.skeleton)
        kept = kept_from_file(self, read)
        self._interrupt_playback()
        file_state = self._file_state()
        self._restore(read.pose)
        show_kept(self, kept)
        self.history.clear()
        self.path = str(path)
        if read.warnings:
            self.history.clean_index = None  # what is shown differs from the file
        self._replaced(file_state)
        return read.warnings

    def save(self, path: str | None = None) -> None:
        """Write the pose atomically to ``path`` (default: the current file).

        Raises:
            GsikFileError, PoseError: nothing was written; the document keeps its path and dirty flag.
        """
        target = path or self.path
        if not target:
            raise gsik.GsikFileError("no file name to save to (use Save As)")
        file_state = self._file_state()
        write_pose(target, self.pose(), skeleton=self.skeleton, **file_fields(kept_state(self)))
        self.path = str(target)
        self.history.set_clean()
        self._emit_file(file_state)

    def new(self) -> None:
        """The standing pose, no file, empty history."""
        self._interrupt_playback()
        file_state = self._file_state()
        self._restore(standing_pose(self.skeleton, {}, self.POSITION_ONLY_BY_DEFAULT, default_levels(self.skeleton)))
        show_kept(self, Kept())  # no library, keys, clip or poles
        self.history.clear()
        self.path = None
        self._replaced(file_state)

    # -- playback: frames shown without undo steps, then recorded as one --------
    def playback(self, frames: Motion | Sequence[Mapping[str, Target | None]],
                 text: str = "Play", frame_time: float = 1 / 30) -> Playback:
        """A :class:`Playback` of a :class:`gsik.anim.motion.Motion` or of a sequence of target dicts.

        A playback running already is stopped first. Any edit, undo, redo or
        load while it runs stops it (what was played so far stays, as one step).
        """
        from gsik_studio.model.playback import Playback

        self._interrupt_playback()
        self._playback = Playback(self, frames, text, frame_time)
        return self._playback

    @property
    def playing(self) -> Playback | None:
        """The running playback, if any."""
        return self._playback

    def show_motion_frame(self, root: str, world_from_root: np.ndarray, q: np.ndarray) -> None:
        """Show one frame of a motion: root, its world transform (4, 4), angles (n_dofs,) [rad]; targets snap on."""
        self._place_root(root, RootPlacement.from_transform(world_from_root))
        self.solver.set_q(np.clip(q, self.skeleton.lower, self.skeleton.upper))
        self._targets = self._snapped_targets()
        self._push_targets()
        self.needs_solving = False
        self.events.pose.emit()

    def drive_targets(self, frame: Mapping[str, Target | None]) -> None:
        """Show one frame of target dicts (None disables an effector), then step the solver once.

        Names that are not effectors of the current root (the root itself) are skipped.
        """
        for name, t in frame.items():
            old = self._targets.get(name)
            if old is None:
                continue
            if t is None:
                self._targets[name] = old.replace(enabled=False)
            else:
                self._targets[name] = driven_target(t, old)
        self._push_targets()
        self.step()
        self.events.pose.emit()

    def record_playback(self, playback: Playback) -> None:
        """A playback ended: what it played becomes one undo step back to ``playback.before``."""
        if self._playback is playback:
            self._playback = None
        file_state = self._file_state()
        self.history.push(Command(playback.text, playback.before, kept_before=kept_state(self)))
        self.needs_solving = True
        self._replaced(file_state)
