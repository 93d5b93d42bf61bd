"""python -m csfh: the csfh command line."""

from .cli.main import main

raise SystemExit(main())
