"""``python -m app``: run gsik-studio."""

from app.main import main

raise SystemExit(main())
