"""``python -m sciviz_gbuf``: the same as the ``sciviz-gbuf`` command."""

from .cli import main

raise SystemExit(main())
