"""File reading and safe writing shared by every format gsik loads and saves (poses, BVH, URDF, skeletons)."""

from __future__ import annotations

import os
import secrets
import stat

from gsik.errors import GsikFileError


def read_bytes(path: str | os.PathLike, what: str = "file") -> bytes:
    """The bytes of a file, or :class:`GsikFileError` naming ``what``, the path and the reason."""
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError as exc:
        raise file_error(f"cannot read {what}", path, exc) from exc


def read_text(path: str | os.PathLike, what: str = "file", encoding: str = "utf-8",
              fallback: str | None = None) -> str:
    """The text of a file, line ends kept as written; every format reads through here.

    Args:
        path: The file.
        what: What the file is, for the message (``"pose file"``).
        encoding: Tried first (``"utf-8-sig"`` also drops a byte-order mark).
        fallback: Tried when ``encoding`` fails (``"latin-1"`` decodes every byte);
            ``None`` makes undecodable text an error.

    Raises:
        GsikFileError: the file cannot be read or decoded, naming it and the reason.
    """
    data = read_bytes(path, what)
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as exc:
        if fallback is not None:
            return data.decode(fallback)
        raise GsikFileError(f"cannot read {what} {os.fspath(path)!r}: not UTF-8 text ({exc.reason})") from None


def file_error(action: str, path: str | os.PathLike, exc: OSError) -> GsikFileError:
    reason = exc.strerror or str(exc) or type(exc).__name__
    err = GsikFileError(f"{action} {os.fspath(path)!r}: {reason}")
    err.errno, err.filename = exc.errno, os.fspath(path)
    return err


def _fsync_directory(directory: str) -> None:
    """Make the rename durable; not possible on every platform, so best effort."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Replace ``path`` with ``text`` (UTF-8) atomically.

    Writes a temporary file in the same directory, fsyncs it and renames it
    over ``path``; on any failure the temporary file is removed and an
    existing ``path`` is left untouched. An existing file's permissions are
    kept.

    Raises:
        GsikFileError: the file cannot be written.
    """
    target = os.path.abspath(os.fspath(path))
    directory, base = os.path.split(target)
    try:
        mode = stat.S_IMODE(os.stat(target).st_mode)
    except FileNotFoundError:
        mode = None
    except OSError as exc:
        raise file_error("cannot write", path, exc) from exc
    tmp = ""
    try:
        flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
        for _ in range(100):
            tmp = os.path.join(directory, f".{base}.{secrets.token_hex(6)}.tmp")
            try:
                fd = os.open(tmp, flags, 0o666)  # 0o666 & ~umask, like a normal new file
                break
            except FileExistsError:
                continue
        else:  # pragma: no cover - 100 random-name collisions
            raise FileExistsError(f"no free temporary name next to {target}")
        with os.fdopen(fd, "wb") as f:
            f.write(text.encode("utf-8"))
            f.flush()
            os.fsync(f.fileno())
        if mode is not None:
            os.chmod(tmp, mode)
        os.replace(tmp, target)
        tmp = ""
    except OSError as exc:
        raise file_error("cannot write", path, exc) from exc
    finally:
        if tmp:
            try:
                os.unlink(tmp)
            except OSError:
                pass
    _fsync_directory(directory)


