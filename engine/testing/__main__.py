"""``python -m xabsl_studio.engine.testing PATH...``: ``xabsl test`` without the installed entry point."""

import sys

from xabsl_studio.engine.testing.cli import main

sys.exit(main())
