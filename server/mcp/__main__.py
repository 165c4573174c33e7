"""``python -m xabsl_studio.server.mcp``: the same as ``xabsl mcp``."""

import sys

from xabsl_studio.server.mcp.cli import main

sys.exit(main())
