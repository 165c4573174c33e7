"""``xabsl lsp``: a language server for XABSL 2 (the Language Server Protocol over stdio or a websocket).

:mod:`xabsl_studio.lsp.project` keeps a behavior set in memory and rechecks it incrementally with the
compiler's own passes (no pygls there); :mod:`xabsl_studio.lsp.server` answers the protocol with pygls;
:mod:`xabsl_studio.lsp.access` is the rule for every file it reads (allowed roots, regular ``.xabsl``
files, a size bound); :mod:`xabsl_studio.lsp.rpc` answers every request without a traceback;
:mod:`xabsl_studio.lsp.bridge` serves websockets (the studio's ``/lsp``, ``xabsl lsp --ws``);
:mod:`xabsl_studio.lsp.cli` is the ``xabsl lsp`` subcommand. Lives outside ``engine`` so the engine stays
importable without pygls.
"""
