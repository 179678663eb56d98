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


#: Largest file any reader takes unless it names its own limit [bytes].
MAX_FILE_BYTES = 64 * 1024 * 1024


def read_bounded(path: str | os.PathLike, what: str = "file", limit: int = MAX_FILE_BYTES) -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes: the one way gsik opens a file it reads.

    Checked before a byte is read, so a hostile path costs a ``stat`` and nothing more:

    - the path is a regular file (``os.stat``): a FIFO (which would block forever), a device (``/dev/zero``,
      ``/dev/urandom``: endless), a directory or a socket is refused;
    - its size is at most ``limit``;
    - it is opened non-blocking and checked again on the open descriptor (``fstat``), so a file swapped for a
      FIFO or a device between the two checks is refused too;
    - at most ``limit + 1`` bytes are read: a file that grew past ``limit`` after the check is refused without
      reading the rest.

    Args:
        path: The file.
        what: What the file is, for the message (``"pose file"``).
        limit: Most bytes accepted.

    Returns:
        The file's bytes (``len <= limit``).

    Raises:
        GsikFileError: naming ``what``, the path and the reason (not a regular file, larger than ``limit``,
            cannot be opened or read).
    """
    action = f"cannot read {what}"
    _check_path(path, action)
    try:
        _check_regular(os.stat(path), path, action, limit)
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
        with os.fdopen(fd, "rb") as f:
            size = _check_regular(os.fstat(f.fileno()), path, action, limit)
            data = _read_at_most(f, size, limit)
    except GsikFileError:
        raise
    except OSError as exc:
        raise file_error(action, path, exc) from exc
    if len(data) > limit:
        raise _too_large(action, path, f"more than {limit:,}", limit)
    return data


#: Bytes read at a time past the size a file had when it was opened [bytes].
_CHUNK = 1 << 20


def _read_at_most(f, size: int, limit: int) -> bytes:
    """The file's bytes, at most ``limit + 1`` of them: its ``size`` at open in one read (never a buffer of
    ``limit`` bytes for a small file), then chunks while it grows."""
    chunks, total, want = [], 0, size + 1
    while total <= limit:
        chunk = f.read(min(want, limit + 1 - total))
        if not chunk:
            break
        chunks.append(chunk)
        total += len(chunk)
        want = _CHUNK
    return chunks[0] if len(chunks) == 1 else b"".join(chunks)


def _check_regular(st: os.stat_result, path: str | os.PathLike, action: str, limit: int) -> int:
    """The size of a regular file of at most ``limit`` bytes; refuses anything else."""
    if not stat.S_ISREG(st.st_mode):
        raise GsikFileError(f"{action} {show_value(os.fspath(path), MAX_PATH_CHARS)}: not a regular file "
                            f"({_kind(st.st_mode)}); gsik reads only regular files")
    if st.st_size > limit:
        raise _too_large(action, path, f"{st.st_size:,}", limit)
    return st.st_size


def _too_large(action: str, path: str | os.PathLike, size: str, limit: int) -> GsikFileError:
    return GsikFileError(f"{action} {show_value(os.fspath(path), MAX_PATH_CHARS)}: the file is {size} bytes; "
                         f"the limit is {limit:,} bytes")


def _kind(mode: int) -> str:
    """What a non-regular file is, in words."""
    for test, name in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a file"


def read_bytes(path: str | os.PathLike, what: str = "file", limit: int = MAX_FILE_BYTES) -> bytes:
    """The bytes of a file, through :func:`read_bounded` (regular files of at most ``limit`` bytes only)."""
    return read_bounded(path, what, limit)


def _check_path(path: str | os.PathLike, action: str) -> None:
    """Refuse a path no file system takes (a NUL character) as a :class:`GsikFileError`, not a ``ValueError``."""
    if "\x00" in os.fspath(path):
        raise GsikFileError(f"{action} {show_value(os.fspath(path), MAX_PATH_CHARS)}: a path cannot hold a NUL "
                            "character")


def read_text(path: str | os.PathLike, what: str = "file", encoding: str = "utf-8",
              fallback: str | None = None, limit: int = MAX_FILE_BYTES) -> str:
    """The text of a file, line ends kept as written; every format reads through here.

    Args:
        path: The file.
        what: What the file is, for the message (``"pose file"``).
        encoding: Tried first (``"utf-8-sig"`` also drops a byte-order mark).
        fallback: Tried when ``encoding`` fails (``"latin-1"`` decodes every byte);
            ``None`` makes undecodable text an error.
        limit: Most bytes read (:func:`read_bounded`).

    Raises:
        GsikFileError: the file cannot be read or decoded, naming it and the reason.
    """
    data = read_bounded(path, what, limit)
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


def atomic_write_text(path: str | os.PathLike, text: str, follow_symlinks: bool = True) -> None:
    """Replace ``path`` with ``text`` (UTF-8) atomically: :func:`atomic_write_bytes`."""
    atomic_write_bytes(path, text.encode("utf-8"), follow_symlinks)


def atomic_write_bytes(path: str | os.PathLike, data: bytes, follow_symlinks: bool = True) -> None:
    """Replace ``path`` with ``data`` atomically; every file gsik writes goes through here.

    Writes a temporary file in the same directory, fsyncs it and renames it
    over ``path``; on any failure the temporary file is removed and an
    existing ``path`` is left untouched. What a save promises besides:

    - an existing file keeps its permissions;
    - a symbolic link is written through: its target gets the new data, the link stays a link; with
      ``follow_symlinks=False`` a symbolic link at ``path`` is refused instead (nothing outside a folder of
      outputs is written through one planted in it; the rename never follows one made meanwhile);
    - a read-only file is refused (:class:`GsikFileError`), never silently replaced;
    - temporary files that earlier saves of ``path`` left behind (a process killed mid-save) are removed.

    Raises:
        GsikFileError: the file cannot be written.
    """
    _check_path(path, "cannot write")
    if follow_symlinks:
        target = os.path.realpath(os.fspath(path))  # through symbolic links: replace the file, not the link
    else:
        target = os.path.abspath(os.fspath(path))
        _refuse_symlink(path, target)
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


def _refuse_symlink(path: str | os.PathLike, target: str) -> None:
    """:class:`GsikFileError` when ``target`` is a symbolic link (it is not followed)."""
    try:
        is_link = stat.S_ISLNK(os.lstat(target).st_mode)
    except FileNotFoundError:
        return
    except OSError as exc:
        raise file_error("cannot write", path, exc) from exc
    if is_link:
        err = GsikFileError(f"cannot write {show_value(os.fspath(path), MAX_PATH_CHARS)}: it is a symbolic link; "
                            "outputs are not written through links (remove it, or choose another --out)")
        err.errno, err.filename = errno.ELOOP, os.fspath(path)
        raise err


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
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0) | getattr(os, "O_NOFOLLOW", 0)
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
