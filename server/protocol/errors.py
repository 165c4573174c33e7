"""The studio server's stage of the exception tree: every refusal of the server derives from here.

``ServerError`` is the server's branch of ``xabsl_studio.engine.errors.XabslError`` (the engine's
module draws the whole tree); its concrete classes live next to the code that raises them
(``ProtocolError``, ``FileError``, ``GraphError``, ``ChannelClosed``, ``TokenError``, ...).
"""

from __future__ import annotations

from xabsl_studio.engine.errors import XabslError

__all__ = ["ServerError"]


class ServerError(XabslError):
    """A request or connection the studio server refuses or loses."""
