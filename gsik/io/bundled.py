"""Where gsik's bundled data (skeletons, pose priors) lives, whichever ``gsik`` was imported.

An installed gsik carries the repository's top-level ``skeletons/`` folder as the package ``gsik.skeletons``. Run
from a clone's root, Python imports the clone's own ``gsik/`` (the current folder comes first on ``sys.path``),
which has no ``skeletons`` package inside: the data is then the clone's ``skeletons/`` folder beside that ``gsik/``.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import gsik


def bundled_dir() -> Path:
    """The folder holding the bundled skeleton files (``biped.yaml``, ``biped_prior.npz``, ...).

    The ``gsik.skeletons`` package when it can be imported (an installed or editable gsik), else the
    ``skeletons/`` folder beside the imported ``gsik/`` package (gsik imported from a source tree).
    """
    try:
        return Path(str(resources.files("gsik.skeletons")))
    except ModuleNotFoundError:
        return Path(gsik.__file__).resolve().parent.parent / "skeletons"
