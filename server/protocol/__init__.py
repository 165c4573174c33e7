"""What the studio's processes and the browser speak: message types, limits and close codes, the pipe.

Imported by both processes and generated into TypeScript (``tsgen``); imports nothing else of the
server. docs/protocol.md describes the websocket and REST side, docs/architecture.md the rest.
"""
