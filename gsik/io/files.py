"""File reading and safe writing shared by every format gsik loads and saves (poses, BVH, URDF, skeletons)."""

from __future__ import annotations

import errno
import os
import secrets
import stat
import time

from gsik.errors import GsikFileError, show_value


#: Longest path quoted whole in a message [characters].
MAX_PATH_CHARS = 240


def read_bytes(path: str | os.PathLike, what: str = "file") -> bytes:
    """The bytes of a file, or :class:`GsikFileError` naming ``what``, the path and the reason."""
    _check_path(path, f"cannot read {what}")
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError as exc:
        raise file_error(f"cannot read {what}", path, exc) from exc


def _check_path(path: str | os.PathLike, action: str) -> None:
    """Refuse a path no file system takes (a NUL character) as a :class:`GsikFileError`, not a ``ValueError``."""
    if "\x00" in os.fspath(path):
        raise GsikFileError(f"{action} {show_value(os.fspath(path), MAX_PATH_CHARS)}: a path cannot hold a NUL "
                            "character")


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
        raise GsikFileError(f"cannot read {what} {show_value(os.fspath(path), MAX_PATH_CHARS)}: not UTF-8 text "
                            f"({exc.reason})") from None


def file_error(action: str, path: str | os.PathLike, exc: OSError) -> GsikFileError:
    reason = exc.strerror or str(exc) or type(exc).__name__
    err = GsikFileError(f"{action} {show_value(os.fspath(path), MAX_PATH_CHARS)}: {reason}")
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


#: A temporary file whose writer cannot be identified counts as stale this long after it was last written [s].
STALE_TEMPORARY_AGE = 600.0


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Replace ``path`` with ``text`` (UTF-8) atomically: :func:`atomic_write_bytes` of its encoding."""
    atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Replace ``path`` with ``data`` atomically.

    Writes a temporary file in the same directory, fsyncs it and renames it
    over ``path``; on any failure the temporary file is removed and an
    existing ``path`` is left untouched. What a save promises besides:

    - an existing file keeps its permissions;
    - a symbolic link is written through: its target gets the new text, the link stays a link;
    - a read-only file is refused (:class:`GsikFileError`), never silently replaced;
    - temporary files that earlier saves of ``path`` left behind (a process killed mid-save) are removed.

    Raises:
        GsikFileError: the file cannot be written.
    """
    _check_path(path, "cannot write")
    target = os.path.realpath(os.fspath(path))  # through symbolic links: replace the file, not the link
    directory, base = os.path.split(target)
    mode = _writable_mode(path, target)
    _remove_stale_temporaries(directory, base)
    tmp = ""
    try:
        tmp, fd = _open_temporary(directory, base, target)
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        if mode is not None:
            os.chmod(tmp, mode)
        os.replace(tmp, target)
        tmp = ""
    except OSError as exc:
        raise file_error("cannot write", path, exc) from exc
    finally:
        _unlink_quietly(tmp)
    _fsync_directory(directory)


def _writable_mode(path: str | os.PathLike, target: str) -> int | None:
    """The permission bits of the existing ``target`` (``None`` when new); a read-only file is refused."""
    try:
        mode = stat.S_IMODE(os.stat(target).st_mode)
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise file_error("cannot write", path, exc) from exc
    if not mode & stat.S_IWUSR or not os.access(target, os.W_OK):
        err = GsikFileError(f"cannot write {show_value(os.fspath(path), MAX_PATH_CHARS)}: the file is read-only "
                            "(make it writable, or save under another name)")
        err.errno, err.filename = errno.EACCES, os.fspath(path)
        raise err
    return mode


def _open_temporary(directory: str, base: str, target: str) -> tuple[str, int]:
    """A new ``.<base>.<pid>.<token>.tmp`` next to ``target``, opened for writing: its path and descriptor."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
    for _ in range(100):
        tmp = os.path.join(directory, f".{base}.{os.getpid()}.{secrets.token_hex(6)}.tmp")
        try:
            return tmp, os.open(tmp, flags, 0o666)  # 0o666 & ~umask, like a normal new file
        except FileExistsError:
            continue
    raise FileExistsError(f"no free temporary name next to {target}")  # pragma: no cover - 100 collisions


def _unlink_quietly(path: str) -> None:
    """Remove ``path`` if given; best effort."""
    if path:
        try:
            os.unlink(path)
        except OSError:
            pass


def _remove_stale_temporaries(directory: str, base: str) -> None:
    """Remove ``.<base>.<pid>.<token>.tmp`` files of saves that can no longer finish.

    A temporary file is stale when the process that wrote it is gone, or, when that cannot be told (another
    machine on a shared folder, an older gsik's name without the process id, Windows), when it has not been
    written for :data:`STALE_TEMPORARY_AGE`. Best effort: a file that cannot be removed stays.
    """
    prefix = f".{base}."
    try:
        entries = [e for e in os.scandir(directory) if e.name.startswith(prefix) and e.name.endswith(".tmp")]
    except OSError:
        return
    now = time.time()
    for entry in entries:
        pid = entry.name[len(prefix):-len(".tmp")].split(".")[0]
        try:
            if _writer_is_gone(pid) or now - entry.stat(follow_symlinks=False).st_mtime > STALE_TEMPORARY_AGE:
                os.unlink(entry.path)
        except OSError:
            pass


def _writer_is_gone(pid: str) -> bool:
    """True when ``pid`` names a process of this machine that no longer runs (POSIX only)."""
    if os.name != "posix" or not pid.isdigit() or int(pid) == os.getpid():
        return False
    try:
        os.kill(int(pid), 0)  # signal 0: only asks whether the process exists
    except ProcessLookupError:
        return True
    except OSError:  # exists, owned by someone else
        return False
    return False
