"""``python -m gsik``: the command line (see :mod:`gsik.cli`)."""

from gsik.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
