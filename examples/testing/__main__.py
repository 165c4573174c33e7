"""``python -m xabsl_studio.examples.testing PATH...``: ``xabsl test`` without the installed entry point."""

import sys

from xabsl_studio.examples.testing.cli import main

sys.exit(main())
