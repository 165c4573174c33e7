"""``xabsl mcp``: the recordings and behavior sets answered to a coding assistant (Model Context Protocol, stdio).

* ``tools``   the answers as plain functions (compile, activation, why, why not, divergence,
              profile, query), files confined to the server's roots
* ``server``  the MCP server (the ``mcp`` package's ``MCPServer``) registering them as tools
* ``cli``     the ``xabsl mcp`` subcommand (entry point ``xabsl.commands``); ``python -m`` runs it too

A layer of its own beside the language server: it imports the engine only, never the studio's
server process (docs/mcp.md).
"""
