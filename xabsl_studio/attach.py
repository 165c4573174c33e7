"""The attach host library's public name: ``from xabsl_studio.attach import serve_engines``.

A program that runs its own XABSL engines (a robot process, a ROS 2 node, a test rig) exposes
them to studios with it; ``xabsl attach HOST:PORT`` opens a studio on them. docs/attach.md is the
guide; the implementation is ``xabsl_studio.server.simulation.host`` (it imports no web framework).
"""

from xabsl_studio.server.protocol.attach import DEFAULT_PORT
from xabsl_studio.server.protocol.tokens import TokenError
from xabsl_studio.server.simulation.host import HostLink, serve_engines

__all__ = ["DEFAULT_PORT", "HostLink", "TokenError", "serve_engines"]
