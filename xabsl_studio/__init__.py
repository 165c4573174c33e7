"""xabsl-studio: the one import package of the project.

The repository keeps its folders where a reader looks for them (``engine/``, ``server/``,
``examples/``, ``lsp/``, ``web/``); this package maps them under one import name of our own
(``xabsl_studio.engine`` and so on: the entries beside this file are links to those folders), so an
installed wheel claims no generic top-level name such as ``engine`` or ``server``. ``web`` is the
built studio UI (``web/dist``), package data of the wheel. docs/architecture.md has the layers.
"""

__version__ = "0.2.0"
