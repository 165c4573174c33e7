"""``python -m lsp``: the language server (the same as ``xabsl lsp``)."""

import sys

from xabsl_studio.lsp.cli import main

sys.exit(main())
