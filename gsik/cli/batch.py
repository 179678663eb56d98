"""A folder of clips through one command: a local process pool, or a Dask distributed cluster; one summary table.

Every command that takes a folder (``gsik retarget|track|learn-prior DIR``)
hands :func:`run_batch` a picklable *work* function, ``work(path) ->
ClipOutcome``, run once per clip:

- locally on a :class:`~concurrent.futures.ProcessPoolExecutor`, one worker
  per clip and core at most (``--workers`` lowers it);
- with ``--scheduler tcp://HOST:PORT`` (or :data:`SCHEDULER_ENV`), on that
  Dask cluster through :class:`distributed.Client` and
  :func:`distributed.as_completed` (``pip install 'gsik[dask]'``).

Either way the workers return their outputs as bytes and this process
writes them into ``--out`` (:class:`~gsik.io.out_folder.OutputFolder`:
plain names, no links, atomic), so the workers need not share its disk and
nothing lands outside ``--out``. A clip that fails, for any reason, is a row
naming the reason; the others go on. The outcomes come back in clip order,
whatever order they finished in.
"""

from __future__ import annotations

import argparse
import os
import re
import time
import traceback
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import NamedTuple

from gsik.cli.common import CommandError
from gsik.cli.progress import progress_for
from gsik.errors import GsikError
from gsik.io.out_folder import OutputFolder

#: The environment variable that names a Dask scheduler when ``--scheduler`` is not given.
SCHEDULER_ENV = "GSIK_SCHEDULER"
#: Exit code of a batch where some clips failed (the others were written).
SOME_FAILED = 4
#: Seconds to wait for a Dask scheduler to answer.
CONNECT_TIMEOUT = 20


class ClipOutcome(NamedTuple):
    """What one clip of a batch gave.

    Attributes:
        clip: The clip's file name.
        cells: The command's columns for the table (empty when the clip failed).
        error: Why the clip failed, ``""`` when it did not.
        code: The exit code the clip alone would give (0; 2 bad input; 3 outside its tolerance; 1 a bug).
        outputs: ``(file name, content)`` to write into ``--out``.
        payload: What the command gathers from every clip (``learn-prior``: the angles), or ``None``.
        seconds: Time the clip took in its worker [s].
    """

    clip: str
    cells: tuple[str, ...] = ()
    error: str = ""
    code: int = 0
    outputs: tuple[tuple[str, bytes], ...] = ()
    payload: object = None
    seconds: float = 0.0

    @property
    def failed(self) -> bool:
        return bool(self.error)


def run_clip(work: Callable[[str], ClipOutcome], path: str) -> ClipOutcome:
    """``work(path)``, timed, with any exception turned into a failed outcome naming the clip and the reason."""
    start = time.perf_counter()
    try:
        outcome = work(path)
    except GsikError as exc:
        outcome = ClipOutcome(Path(path).name, error=" ".join(str(exc).split()), code=exc.exit_code)
    except MemoryError:
        outcome = ClipOutcome(Path(path).name, error="not enough memory for this clip", code=2)
    except Exception as exc:  # noqa: BLE001 - a bug on one clip must not stop the batch; reported with its place
        where = traceback.extract_tb(exc.__traceback__)[-1]
        outcome = ClipOutcome(Path(path).name, error=f"unexpected {type(exc).__name__}: {exc} "
                              f"({Path(where.filename).name}:{where.lineno})", code=1)
    return outcome._replace(seconds=time.perf_counter() - start)


def folder_clips(folder: str, out: str | None, out_suffixes: Sequence[str] = (".bvh",)) -> list[Path]:
    """The ``.bvh`` files under the folder (its subfolders too, as ``learn-prior`` reads them) in path order;
    refuses an empty folder, two clips of one file name (their outputs would share a name in ``--out``) and an
    ``--out`` that names a file."""
    try:
        clips = sorted(p for p in Path(folder).rglob("*") if p.suffix.lower() == ".bvh" and p.is_file()
                       and not p.is_symlink())
    except OSError as exc:
        raise CommandError(f"cannot list folder {folder!r}: {exc.strerror or exc}") from None
    if not clips:
        raise CommandError(f"folder {folder!r} holds no .bvh files")
    seen: dict[str, Path] = {}
    for p in clips:
        if p.name in seen:
            raise CommandError(f"folder {folder!r} holds two clips named {p.name!r} ({seen[p.name]} and {p}); "
                               "their outputs would share one name")
        seen[p.name] = p
    if out and Path(out).suffix.lower() in out_suffixes:
        raise CommandError(f"--out {out!r}: with a folder of clips, --out names a folder")
    return clips


def add_batch_options(p: argparse.ArgumentParser) -> None:
    """``--workers`` and ``--scheduler``: where a folder of clips runs."""
    g = p.add_argument_group("a folder of clips")
    g.add_argument("--workers", type=_count, metavar="N",
                   help="local worker processes (default: one per core; never more than clips or cores)")
    g.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                   help=f"run the clips on this Dask distributed cluster (default: ${SCHEDULER_ENV} if set, else "
                        "the local pool; needs pip install 'gsik[dask]')")


def _count(text: str) -> int:
    """A whole number >= 1 (``--workers``)."""
    if not text.strip().isdigit() or int(text) < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}")
    return int(text)


def scheduler_address(args: argparse.Namespace) -> str | None:
    """``--scheduler``, else :data:`SCHEDULER_ENV`, else ``None`` (the local pool); checked to be an address."""
    address = getattr(args, "scheduler", None) or os.environ.get(SCHEDULER_ENV) or None
    if address is not None and not re.fullmatch(r"[a-z][a-z0-9+]*://\S+", address):
        source = "--scheduler" if getattr(args, "scheduler", None) else SCHEDULER_ENV
        raise CommandError(f"{source} {address!r}: expected a Dask scheduler address such as tcp://HOST:PORT")
    return address


def local_workers(requested: int | None, n_clips: int) -> int:
    """Worker processes for ``n_clips`` clips: ``requested`` (default one per core), at most one per clip and core."""
    cores = os.cpu_count() or 1
    return max(1, min(requested or cores, n_clips, cores))


class BatchResult(NamedTuple):
    """A batch's outcomes, in clip order, and the number of files written into ``--out``."""

    outcomes: list[ClipOutcome]
    written: int


def run_batch(args: argparse.Namespace, work: Callable[[str], ClipOutcome], clips: Sequence[Path], label: str,
              folder: OutputFolder | None = None) -> BatchResult:
    """``work`` on every clip, locally or on the Dask cluster the options name; each clip's outputs written into
    ``folder`` as soon as it is done (a failed write fails that clip)."""
    paths = [str(p) for p in clips]
    address = scheduler_address(args)
    done: dict[str, ClipOutcome] = {}
    written = 0
    with progress_for(args, f"{label} {len(paths)} clips") as progress:
        if address is None:
            results = _run_local(work, paths, local_workers(getattr(args, "workers", None), len(paths)))
        else:
            results = _run_dask(work, paths, address)
        for path, outcome in results:
            done[path], n = _write(outcome, folder)
            written += n
            progress(len(done), len(paths))
    return BatchResult([done[p] for p in paths], written)


def _run_local(work, paths: list[str], workers: int) -> Iterator[tuple[str, ClipOutcome]]:
    """Every clip on a pool of ``workers`` processes: ``(path, outcome)`` as they finish."""
    with ProcessPoolExecutor(max_workers=workers) as pool:
        jobs = {pool.submit(run_clip, work, p): p for p in paths}
        for job in as_completed(jobs):
            yield jobs[job], _result(job, jobs[job])


def _run_dask(work, paths: list[str], address: str) -> Iterator[tuple[str, ClipOutcome]]:
    """Every clip as one task on the Dask cluster at ``address``: ``(path, outcome)`` as they finish."""
    try:
        from distributed import Client
        from distributed import as_completed as dask_completed
    except ImportError:
        raise CommandError(f"--scheduler {address}: Dask is not installed (pip install 'gsik[dask]')") from None
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError) as exc:
        raise CommandError(f"cannot reach the Dask scheduler at {address}: {exc}") from None
    with client:
        jobs = {client.submit(run_clip, work, p, pure=False): p for p in paths}
        for job in dask_completed(list(jobs)):
            yield jobs[job], _result(job, jobs[job])


def _result(job, path: str) -> ClipOutcome:
    """A finished job's outcome; a job that died (a killed worker, a lost connection) fails its clip."""
    try:
        return job.result()
    except Exception as exc:  # noqa: BLE001 - reported as the clip's failure
        return ClipOutcome(Path(path).name, error=f"the worker failed: {type(exc).__name__}: {exc}", code=1)


def _write(outcome: ClipOutcome, folder: OutputFolder | None) -> tuple[ClipOutcome, int]:
    """Write ``outcome``'s outputs into ``folder``: the outcome without them (failed if a write failed), files
    written."""
    written = 0
    if folder is not None and not outcome.failed:
        try:
            for name, data in outcome.outputs:
                folder.write_bytes(name, data)
                written += 1
        except GsikError as exc:
            outcome = outcome._replace(error=str(exc), code=exc.exit_code)
    return outcome._replace(outputs=()), written


def format_table(columns: Sequence[str], outcomes: Sequence[ClipOutcome], left: Sequence[int] = ()) -> str:
    """The summary: one line per clip, its cells under ``columns`` (right-aligned but the ``left`` ones) and its
    seconds, or its error."""
    columns = (*columns, "seconds")
    outcomes = [o._replace(cells=(*o.cells, f"{o.seconds:.2f}")) for o in outcomes]
    w = max([4, *(len(o.clip) for o in outcomes)])
    widths = [max([len(c), *(len(o.cells[k]) for o in outcomes if len(o.cells) > k)]) for k, c in enumerate(columns)]

    def line(name: str, cells: Sequence[str]) -> str:
        return "  ".join([f"{name:<{w}}", *(f"{c:<{widths[k]}}" if k in left else f"{c:>{widths[k]}}"
                                             for k, c in enumerate(cells))]).rstrip()

    head = line("clip", columns)
    lines = [head, "-" * len(head)]
    for o in outcomes:
        lines.append(f"{o.clip:<{w}}  error: {o.error}" if o.failed else line(o.clip, o.cells))
    return "\n".join(lines)


def batch_exit(outcomes: Sequence[ClipOutcome]) -> int:
    """0 when every clip went through, else :data:`SOME_FAILED`."""
    return SOME_FAILED if any(o.failed for o in outcomes) else 0


def summary_line(outcomes: Sequence[ClipOutcome], written: int, out: str | None) -> str:
    """``"N of M clips failed; wrote K files to DIR"`` (the parts that apply)."""
    failed = sum(o.failed for o in outcomes)
    parts = [f"{failed} of {len(outcomes)} clips failed" if failed else f"all {len(outcomes)} clips done"]
    if out is not None:
        parts.append(f"wrote {written} files to {out}")
    return "; ".join(parts)
