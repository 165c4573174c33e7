"""The OpenAPI vocabulary of the studio's refusals: the error body and the documented error statuses.

Every router (``xabsl_studio.server.api.app``, ``xabsl_studio.server.api.profile``, ...) documents the
statuses it answers with
:func:`error_responses`, so the OpenAPI document stays true (schemathesis checks it against the
live app in tests/server/api/test_schema.py).
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field

from xabsl_studio.server.protocol.limits import MAX_BODY_BYTES, MAX_HEAD_BYTES, MAX_TARGET_BYTES


class ErrorBody(BaseModel):
    """A refused request: what was wrong."""

    detail: str = Field(description="the reason, for a human")


_WHY = {
    400: "a malformed request (its text says what is wrong)",
    401: "the server requires a token and none or a wrong one was given",
    403: "a foreign Origin, or a path outside the behavior folders",
    404: "no such file, folder, behavior set or option",
    409: "the file changed since the version given, or the target exists; a command that does not fit the session now",
    413: f"a request body over {MAX_BODY_BYTES // 1024} KiB",
    414: f"a request target (path and query) over {MAX_TARGET_BYTES // 1024} KiB",
    415: "a file that is not UTF-8 text",
    422: "saved or compiled, but a behavior set has errors (the body lists them); or a malformed parameter",
    428: "overwriting without the version edited",
    431: f"a request head (request line and headers) over {MAX_HEAD_BYTES // 1024} KiB",
    503: "Graphviz (dot) is not installed",
}


_ERROR_JSON = {"application/json": {"schema": {"$ref": "#/components/schemas/ErrorBody"}}}
# 422 is also FastAPI's answer to a malformed parameter or body.
_UNPROCESSABLE_JSON = {
    "application/json": {
        "schema": {
            "anyOf": [{"$ref": "#/components/schemas/ErrorBody"}, {"$ref": "#/components/schemas/HTTPValidationError"}]
        }
    }
}


def error_responses(*codes: int) -> dict[int | str, dict[str, Any]]:
    """OpenAPI ``responses`` for error statuses a route answers (besides those of every /api route).

    Every route may answer 401 and 403 (the token, Origin and Host checks) and 414 and 431 (an
    oversized request): ``server/api/security.py`` answers them before the route is reached.
    """
    return {
        code: {"description": _WHY[code], "content": _UNPROCESSABLE_JSON if code == 422 else _ERROR_JSON}
        for code in sorted({401, 403, 414, 431, *codes})
    }
