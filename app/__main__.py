"""``python -m gsik_studio``: run gsik-studio."""

from gsik_studio.main import main

raise SystemExit(main())
