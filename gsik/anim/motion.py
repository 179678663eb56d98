"""Animation as plain data: joint angles per frame, with the root pinned per frame."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gsik.errors import GsikError
from gsik.kinematics import world_frames
from gsik.skeleton import Skeleton

#: Seconds per frame a motion may have [s]: 10,000 frames per second to one frame in 1000 s (a shorter time makes
#: the frame rate overflow, a longer one a clip that never plays).
FRAME_TIME_RANGE = (1e-4, 1e3)


@dataclass(frozen=True, eq=False)
class Motion:
    """A sequence of poses of one skeleton.

    The IK root may change from frame to frame (a walk plants each foot in
    turn); each frame says which frame was the root and where it stood, so
    the world pose of every frame is fully determined.

    Attributes:
        skeleton: The skeleton.
        q: (n_frames, n_dofs) joint angles [rad].
        roots: (n_frames,) name of the IK root in each frame.
        world_from_root: (n_frames, 4, 4) world transform of that root.
        frame_time: Seconds per frame [s].
    """

    skeleton: Skeleton
    q: np.ndarray
    roots: tuple[str, ...]
    world_from_root: np.ndarray
    frame_time: float

    def __post_init__(self):
        q = np.array(self.q, dtype=float)
        W = np.array(self.world_from_root, dtype=float)
        n = q.shape[0] if q.ndim == 2 else -1
        if q.ndim != 2 or q.shape[1] != self.skeleton.n_dofs:
            raise GsikError(f"motion angles must have shape (n_frames, {self.skeleton.n_dofs}), got {q.shape}")
        if W.shape != (n, 4, 4):
            raise GsikError(f"motion world_from_root must have shape ({n}, 4, 4), got {W.shape}")
        if len(self.roots) != n:
            raise GsikError(f"motion needs one root name per frame ({n}), got {len(self.roots)}")
        if not FRAME_TIME_RANGE[0] <= self.frame_time <= FRAME_TIME_RANGE[1]:
            raise GsikError(f"motion frame_time must be from {FRAME_TIME_RANGE[0]:g} to {FRAME_TIME_RANGE[1]:g} "
                            f"seconds, got {self.frame_time!r}")
        for name in set(self.roots):
            self.skeleton.frame_of(name)
        for a in (q, W):
            a.flags.writeable = False
        object.__setattr__(self, "q", q)
        object.__setattr__(self, "world_from_root", W)
        object.__setattr__(self, "roots", tuple(self.roots))

    @property
    def n_frames(self) -> int:
        return self.q.shape[0]

    def frames(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """World rotations (n_frames_sk, 3, 3) and positions (n_frames_sk, 3) [m] of every skeleton frame at frame ``i``."""
        return world_frames(self.skeleton, self.q[i], self.world_from_root[i], self.roots[i])

    def positions(self) -> np.ndarray:
        """World positions (n_frames, n_skeleton_frames, 3) [m] of every skeleton frame, every frame."""
        return np.stack([self.frames(i)[1] for i in range(self.n_frames)])
