"""A folder of outputs that nothing escapes: plain file names only, no symbolic links followed, atomic writes."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from gsik.errors import GsikFileError, show_value
from gsik.io.files import MAX_PATH_CHARS, atomic_write_bytes


@dataclass(frozen=True)
class OutputFolder:
    """The folder a batch writes into (``--out DIR``), resolved once.

    Every output is a plain file name directly inside it: a name with a path
    separator, ``.`` or ``..``, a name whose place resolves elsewhere, and a
    symbolic link already standing at the name are refused
    (:class:`GsikFileError`); files are replaced atomically
    (:func:`gsik.io.files.atomic_write_bytes`, never through a link).

    Attributes:
        root: The folder, absolute and with its own links resolved.
        given: The folder as the user named it (for messages).
    """

    root: Path
    given: str

    @classmethod
    def create(cls, path: str | os.PathLike) -> OutputFolder:
        """The folder ``path``, created with its parents if needed; :class:`GsikFileError` if it cannot be."""
        given = os.fspath(path)
        try:
            Path(given).mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise GsikFileError(f"cannot create folder {show_value(given, MAX_PATH_CHARS)}: "
                                f"{exc.strerror or exc}") from None
        return cls(Path(os.path.realpath(given)), given)

    def path(self, name: str) -> Path:
        """Where output ``name`` goes: checked to be a plain file name directly inside the folder, not a link."""
        bad = (not name or name in (".", "..") or "\x00" in name or "/" in name
               or (os.altsep is not None and os.altsep in name) or os.sep in name)
        where = self.root / name
        if bad or Path(os.path.realpath(where.parent)) != self.root:
            raise GsikFileError(f"output name {show_value(name)} would leave --out {self.given!r}; "
                                "outputs are plain file names inside it")
        if where.is_symlink():
            raise GsikFileError(f"cannot write {show_value(os.path.join(self.given, name), MAX_PATH_CHARS)}: it is "
                                "a symbolic link; outputs are not written through links (remove it, or choose "
                                "another --out)")
        return where

    def write_bytes(self, name: str, data: bytes) -> Path:
        """Write ``data`` as ``name`` inside the folder, atomically; the path written."""
        where = self.path(name)
        atomic_write_bytes(where, data, follow_symlinks=False)
        return where

    def write_text(self, name: str, text: str) -> Path:
        """Write ``text`` (UTF-8) as ``name`` inside the folder, atomically; the path written."""
        return self.write_bytes(name, text.encode("utf-8"))
