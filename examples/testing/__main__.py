"""``python -m examples.testing PATH...``: ``xabsl test`` without the installed entry point."""

import sys

from examples.testing.cli import main

sys.exit(main())
