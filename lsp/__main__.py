"""``python -m lsp``: the language server (the same as ``xabsl lsp``)."""

import sys

from lsp.cli import main

sys.exit(main())
