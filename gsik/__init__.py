"""gsik: real-time character inverse kinematics by Projected Gauss-Seidel.

After Kenwright (2012), "Real-Time Character Inverse Kinematics using the
Gauss-Seidel Iterative Approximation Method". NumPy (and numba, when
installed) only: gsik never imports Qt, PyVista or VTK.
"""

from gsik.errors import (
    BvhError,
    GaitError,
    GsikError,
    GsikFileError,
    HumanoidError,
    PoseError,
    ScenarioError,
    SkeletonError,
    SolverError,
    TargetError,
    UrdfError,
)
from gsik.skeleton import JointSpec, RotationSpec, SegmentSpec, SiteSpec, Skeleton, build_skeleton
from gsik.io.skeleton_yaml import bundled_skeletons, load_skeleton, skeleton_from_dict, skeleton_from_yaml
from gsik.solver import SolveResult, Solver, SolverSettings, Status
from gsik.targets import Target

__version__ = "0.1.0"

__all__ = [
    "BvhError", "GaitError", "GsikError", "ScenarioError", "GsikFileError", "HumanoidError", "PoseError", "SkeletonError", "SolverError", "TargetError",
    "UrdfError", "JointSpec", "RotationSpec", "SegmentSpec", "SiteSpec", "Skeleton", "build_skeleton",
    "bundled_skeletons", "load_skeleton", "skeleton_from_dict", "skeleton_from_yaml", "SolveResult", "Solver",
    "SolverSettings", "Status", "Target", "__version__",
]
