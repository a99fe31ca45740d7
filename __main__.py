"""``python -m omninoise``: the ``omninoise`` command line."""
from .cli.main import main

raise SystemExit(main())
