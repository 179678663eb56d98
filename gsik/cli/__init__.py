"""The ``gsik`` command line: inspect skeletons, solve poses, walk, run scenarios, track clips, benchmark.

Run ``gsik --help`` (or ``python -m gsik --help``) and ``gsik COMMAND --help``.

Exit codes: 0 success; 2 bad input (an unknown skeleton, a missing or
malformed file, a bad option; the message goes to stderr as
``gsik: error: ...``); 3 a result outside its tolerance, not written
(``--force`` writes it); 4 some clips of a folder failed (the others were
written); 1 an unexpected failure; 130 interrupted. A solve that
cannot reach its targets is not an error: the best reach is reported (and
written) with its status.

A progress bar is drawn on stderr for work that takes more than a second,
when stderr is a terminal or with ``--progress``.

Layout: :mod:`~gsik.cli.parser` (the options and :func:`main`),
:mod:`~gsik.cli.commands` (one ``cmd_*`` per command), :mod:`~gsik.cli.info`
(``gsik info``), :mod:`~gsik.cli.common` (helpers the commands share),
:mod:`~gsik.cli.progress` (the progress bar), :mod:`~gsik.cli.batch` (a folder of clips on a local pool or a
Dask cluster).
"""

from gsik.cli.common import PROG, CommandError
from gsik.cli.parser import build_parser, main
from gsik.cli.progress import Progress

__all__ = ["PROG", "CommandError", "Progress", "build_parser", "main"]
