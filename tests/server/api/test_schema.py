"""The OpenAPI document is true: schemathesis against the live app (real uvicorn), every check.

Bounded and derandomized (hypothesis ``derandomize``: the same cases on every run), so a failure
here is a real change, not luck. The demo example runs in a private copy, so the files the
fuzzer writes, renames and deletes are its own.
"""

from __future__ import annotations

import shutil
from collections.abc import Iterator

import pytest
import schemathesis
from hypothesis import HealthCheck, given, settings
from hypothesis.errors import Unsatisfiable
from schemathesis import GenerationMode

from tests.server.conftest import REPO, LiveServer
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.session.live import Session

# PUT needs the version edited, from If-Match *or* the body's "version": OpenAPI cannot say
# "one of the two", so a PUT without either is schema-valid and still (rightly) a 428.
#: Cases per operation and mode: bounded, so the test takes seconds.
EXAMPLES = 20

CONFIG = """
[checks]
enabled = true

[[operations]]
include-method = "PUT"
include-path = "/api/files/{path}"
checks.positive_data_acceptance.expected-statuses = ["2xx", "3xx", "401", "403", "404", "409", "428"]
"""


@pytest.fixture(scope="module")
def live_api(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveServer]:
    folder = tmp_path_factory.mktemp("schema") / "demo"
    shutil.copytree(REPO / "examples" / "demo", folder)
    session = Session(BenchExample(folder), seed=3, speed=2.0)
    with LiveServer(session) as server:
        yield server
    session.stop()


@pytest.fixture(scope="module")
def api_schema(live_api: LiveServer) -> schemathesis.BaseSchema:
    config = schemathesis.Config.from_str(CONFIG)
    return schemathesis.openapi.from_url(f"{live_api.url}/api/openapi.json", config=config)


@pytest.mark.parametrize("mode", [GenerationMode.POSITIVE, GenerationMode.NEGATIVE])
def test_every_operation_answers_as_documented(
    api_schema: schemathesis.BaseSchema, live_api: LiveServer, mode: GenerationMode
) -> None:
    failures: list[str] = []
    operations = [result.ok() for result in api_schema.get_all_operations()]
    assert len(operations) >= 13
    for operation in operations:

        @given(case=operation.as_strategy(generation_mode=mode))
        @settings(max_examples=EXAMPLES, derandomize=True, deadline=None, suppress_health_check=list(HealthCheck))
        def run(case: schemathesis.Case) -> None:
            case.call_and_validate(base_url=live_api.url)

        try:
            run()
        except Unsatisfiable:  # negative mode: nothing of this operation can be made invalid (no inputs)
            assert mode is GenerationMode.NEGATIVE, operation.label
        except Exception as error:  # every operation runs; the assertion lists all that failed
            failures.append(f"{operation.label}: {error}")
    assert not failures, "\n\n".join(failures)


def test_the_schema_documents_commands_and_errors(live_api: LiveServer) -> None:
    import httpx2 as httpx

    document = httpx.get(f"{live_api.url}/api/openapi.json").json()
    command = document["paths"]["/api/command"]["post"]
    assert command["requestBody"]["content"]["application/json"]["schema"] == {"$ref": "#/components/schemas/Command"}
    assert {"200", "400", "409", "422"} <= set(command["responses"])
    assert "ForceOption" in document["components"]["schemas"]
    log = document["paths"]["/api/log"]["get"]["responses"]["200"]["content"]
    assert list(log) == ["application/x-ndjson"]
    options = httpx.options(f"{live_api.url}/api/files/options/play.xabsl")
    assert options.status_code == 405
    assert set(options.headers["allow"].split(", ")) == {"DELETE", "GET", "HEAD", "PATCH", "POST", "PUT"}
