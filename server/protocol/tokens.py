"""The token rules every listening end of the project follows: the studio and an attached host.

One owner for them (``xabsl_studio.server.api.security`` applies them to HTTP and websockets,
``xabsl_studio.server.simulation.host`` to the attach socket): a loopback end may go without a
token; off loopback one is required, at least :data:`MIN_TOKEN_CHARS` long; an empty or
non-printable one is refused everywhere; tokens are compared in constant time.
"""

from __future__ import annotations

import ipaddress
import secrets
from collections.abc import Iterable

from xabsl_studio.server.protocol.errors import ServerError

#: The shortest token accepted off loopback (128 bits as URL-safe base64).
MIN_TOKEN_CHARS = 22


class TokenError(ServerError, ValueError):
    """A token that must not be used: empty, or too short for a server off loopback."""


def is_loopback(host: str) -> bool:
    """True for a loopback host name or address (``127.0.0.1``, ``::1``, ``localhost``)."""
    name = host.strip("[]").lower()
    if name == "localhost":
        return True
    try:
        return ipaddress.ip_address(name).is_loopback
    except ValueError:
        return False


def new_token() -> str:
    """A fresh random token (URL safe, 192 bits)."""
    return secrets.token_urlsafe(24)


def check_token(token: str | None, loopback: bool) -> None:
    """Refuse a token that would not protect anything.

    An empty token (``--token "$UNSET"``) is refused everywhere; off loopback, where the token is
    the only guard, one shorter than :data:`MIN_TOKEN_CHARS` is refused too.

    Raises:
        TokenError: with the message to show the user.
    """
    if token is None:
        return
    if not token.strip():
        raise TokenError("the token is empty (an unset shell variable?): give a real one or leave --token out")
    if not all("!" <= c <= "~" for c in token):
        raise TokenError("the token must be printable ASCII without spaces (it travels in headers and URLs)")
    if not loopback and len(token) < MIN_TOKEN_CHARS:
        raise TokenError(
            f"the token is {len(token)} characters; off loopback it must have at least {MIN_TOKEN_CHARS} "
            "(leave --token out to get a generated one, or use python -c 'import secrets; "
            "print(secrets.token_urlsafe())')"
        )


def token_matches(given: Iterable[str], expected: str) -> bool:
    """True when one of the presented tokens is ``expected``; every one is compared in constant time."""
    wanted = expected.encode()
    ok = False
    for candidate in given:
        # Every candidate is compared (no early exit); an empty one never matches.
        same = secrets.compare_digest(candidate.encode("utf-8", "surrogateescape"), wanted)
        ok = ok or (same and bool(candidate))
    return ok
