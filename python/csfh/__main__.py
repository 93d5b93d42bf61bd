"""python -m csfh: the csfh command line."""

from .cli import main

raise SystemExit(main())
