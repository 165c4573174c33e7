"""Worlds for any tool: the plug-in loader (``loader``) and the bench world (``bench``).

``xabsl serve``, ``xabsl test``, tournaments and tests load worlds through here; nothing in this
package needs the server.
"""
