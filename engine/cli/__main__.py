"""``python -m xabsl_studio.engine.cli``: the same as the ``xabsl`` console script."""

import sys

from xabsl_studio.engine.cli import main

sys.exit(main())
