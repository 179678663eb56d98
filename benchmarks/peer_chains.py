"""The chain problems of ``bench_peers.py``: one arm and one leg of the bundled biped, as small URDF files.

Both peers read the same file: gsik through :func:`gsik.io.urdf_skeleton.skeleton_from_urdf`, placo through its
``RobotWrapper``. Segment lengths and joint ranges are the biped's (``skeletons/biped.yaml``), read from the bundled
YAML so the chains follow it:

- **arm** (7 DOF, shoulder to hand): the left shoulder's x, y, z, the elbow's x, then a wrist (z, y, x) 0.25 m down
  the forearm with the hand 0.08 m beyond it: the biped's 0.33 m from elbow to hand, the wrist and its ranges the
  bundled humanoid's (the biped with wrists; the biped itself has none).
- **leg** (6 DOF, hip to foot): the left hip's x, y, z, the knee's x, the ankle's x and y (its twist left out: the
  hip's twist turns the foot about the same line), the foot site as the biped places it.

Every URDF joint is one revolute DOF: a ball joint is three, chained by zero-length links, in the biped's order.
The chain's root link sits at the world origin; :attr:`Chain.rest` is the biped's rest pose of those DOFs.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from gsik.io.bundled import bundled_dir

_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


@dataclass(frozen=True)
class Chain:
    """One chain problem.

    Attributes:
        name: ``"arm"`` or ``"leg"``.
        urdf: The URDF text.
        effector: The effector link's name (the chain's last link).
        dof_names: (n_dofs,) URDF joint names, root to effector.
        rest: (n_dofs,) the biped's rest angles of those DOFs [rad].
        bent: (n_dofs,) a pose with the limb bent halfway, away from its straight-limb singularity [rad]: where
            the tracking benchmark starts.
    """

    name: str
    urdf: str
    effector: str
    dof_names: tuple[str, ...]
    rest: np.ndarray
    bent: np.ndarray

    def write(self, folder: Path) -> Path:
        """Write ``<name>.urdf`` into ``folder``; returns its path."""
        path = Path(folder) / f"{self.name}.urdf"
        path.write_text(self.urdf)
        return path


def _joints(skeleton: str) -> dict[str, dict]:
    doc = yaml.safe_load((bundled_dir() / f"{skeleton}.yaml").read_text())
    joints = {j["name"]: j for j in doc["joints"]}
    for s in doc["sites"]:
        joints[s["name"]] = s
    return joints


def _urdf(name: str, links: list[tuple[str, tuple, dict | None]], effector: str, tip: tuple) -> tuple[str, tuple]:
    """URDF text of a chain: ``links`` is ``(joint name, offset from the previous joint [m], rotation)`` per DOF,
    ``rotation`` ``{axis, limits}``; the effector a fixed link ``tip`` [m] past the last DOF."""
    out = [f'<robot name="biped_{name}">', '  <link name="base"/>']
    parent = "base"
    names = []
    for joint, offset, rot in links:
        lo, hi = rot["limits"]
        child = f"{joint}_link"
        out += [f'  <link name="{child}"/>',
                f'  <joint name="{joint}" type="revolute">',
                f'    <parent link="{parent}"/><child link="{child}"/>',
                f'    <origin xyz="{offset[0]!r} {offset[1]!r} {offset[2]!r}" rpy="0 0 0"/>',
                f'    <axis xyz="{" ".join(map(repr, _AXES[rot["axis"]]))}"/>',
                f'    <limit lower="{lo!r}" upper="{hi!r}" effort="100" velocity="100"/>',
                '  </joint>']
        parent = child
        names.append(joint)
    out += [f'  <link name="{effector}"/>',
            f'  <joint name="{effector}_fixed" type="fixed">',
            f'    <parent link="{parent}"/><child link="{effector}"/>',
            f'    <origin xyz="{tip[0]!r} {tip[1]!r} {tip[2]!r}" rpy="0 0 0"/>',
            '  </joint>', '</robot>', '']
    return "\n".join(out), tuple(names)


def _ball(joints: dict, joint: str, offset, n: int | None = None) -> list:
    """The first ``n`` (default all) rotations of ``joint``, the first at ``offset``, the others at 0."""
    rots = joints[joint]["rotations"][:n]
    zero = (0.0, 0.0, 0.0)
    return [(f"{joint}_{r['axis']}", tuple(offset) if i == 0 else zero, r) for i, r in enumerate(rots)]


def _rest(links: list) -> np.ndarray:
    return np.array([float(r.get("rest", min(max(0.0, r["limits"][0]), r["limits"][1]))) for _, _, r in links])


def arm() -> Chain:
    """The 7-DOF arm: the biped's left shoulder and elbow, the humanoid's left wrist (see the module)."""
    biped, humanoid = _joints("biped"), _joints("humanoid")
    elbow_to_hand = biped["left_hand"]["offset"]  # [0, 0, -0.33]
    wrist_at = humanoid["left_wrist"]["offset"]  # [0, 0, -0.25]
    tip = tuple(float(a - b) for a, b in zip(elbow_to_hand, wrist_at))
    links = (_ball(biped, "left_shoulder", (0.0, 0.0, 0.0)) + _ball(biped, "left_elbow", biped["left_elbow"]["offset"])
             + _ball(humanoid, "left_wrist", wrist_at))
    text, names = _urdf("arm", links, "hand", tip)
    # Shoulder forward 0.6 rad and out 0.2 rad, elbow bent 1.2 rad.
    return Chain("arm", text, "hand", names, _rest(links), np.array([0.6, 0.2, 0.0, 1.2, 0.0, 0.0, 0.0]))


def leg() -> Chain:
    """The 6-DOF leg: the biped's left hip, knee and ankle (x, y), the foot where the biped has it."""
    biped = _joints("biped")
    links = (_ball(biped, "left_hip", (0.0, 0.0, 0.0)) + _ball(biped, "left_knee", biped["left_knee"]["offset"])
             + _ball(biped, "left_ankle", biped["left_ankle"]["offset"], 2))
    text, names = _urdf("leg", links, "foot", tuple(biped["left_foot"]["offset"]))
    # Hip 0.6 rad forward, knee bent 0.8 rad, ankle 0.2 rad: the sole level (hip + knee + ankle = 0).
    return Chain("leg", text, "foot", names, _rest(links), np.array([0.6, 0.0, 0.0, -0.8, 0.2, 0.0]))


CHAINS = {"arm": arm, "leg": leg}
