"""``xabsl lsp``: a language server for XABSL 2 (the Language Server Protocol over stdio or a websocket).

:mod:`xabsl_studio.lsp.project` keeps a behavior set in memory and rechecks it incrementally with the
compiler's own passes (no pygls there); :mod:`xabsl_studio.lsp.server` answers the protocol with pygls;
:mod:`xabsl_studio.lsp.cli` is the ``xabsl lsp`` subcommand. Lives outside ``engine`` so the engine stays
importable without pygls.
"""
