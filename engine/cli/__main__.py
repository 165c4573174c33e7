"""``python -m engine.cli``: the same as the ``xabsl`` console script."""

import sys

from engine.cli import main

sys.exit(main())
