"""How fast does ``xabsl lsp`` answer while someone types in a large behavior set?

Generates a 180-option behavior set with benchmarks/compile_speed.py's generator (about 200
files), starts the language server as a separate process and speaks JSON-RPC to it over stdio,
as an editor does (tests/lsp/client.py). It opens one option file, then many times: changes one
character (a keystroke) and waits for the diagnostics the server publishes for that file; and
asks for completion in a call's parameter list and where everything is offered (after an
``if (``: every symbol, option and basic behavior, their documentation left to resolve). It
prints the median and 90th percentile of each, the goals (diagnostics under 100 ms,
completion under 50 ms), and the ratio to a full compile of the set in this process.

Run::

    .venv/bin/python benchmarks/lsp_speed.py [--options 180] [--keystrokes 40]
"""

from __future__ import annotations

import argparse
import re
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks.compile_speed import generate_behavior_set  # noqa: E402
from tests.lsp.client import LspClient, uri  # noqa: E402
from xabsl_studio.engine.lang import compile_file  # noqa: E402
from xabsl_studio.lsp.project import Project  # noqa: E402

DIAGNOSTICS_GOAL = 0.100
COMPLETION_GOAL = 0.050


def pick_file(agents: Path) -> tuple[Path, int, int]:
    """An option file with an option call in an action: right after the call's '(' (its
    parameters are offered) and right after an expression's '(' (everything is offered)."""
    calls = re.compile(r"^\s+(opt\d+)\(", re.MULTILINE)
    for path in sorted(agents.parent.rglob("*.xabsl")):
        text = path.read_text(encoding="utf-8")
        call = calls.search(text)
        general = text.find("if (")
        if "option " in text and call and general >= 0:
            return path, call.end(), general + len("if (")
    raise SystemExit("no option file with an option call")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--options", type=int, default=180)
    parser.add_argument("--keystrokes", type=int, default=40)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as folder:
        agents = generate_behavior_set(Path(folder), options=args.options)
        files = len(list(Path(folder).rglob("*.xabsl")))
        started = time.perf_counter()
        compilation = compile_file(str(agents), base=folder)
        full = time.perf_counter() - started
        path, call, general_at = pick_file(agents)
        text = path.read_text(encoding="utf-8")
        client = LspClient()
        try:
            client.initialize(folder)
            client.open(path, text)
            client.wait_diagnostics(path, timeout=120)

            def position(offset: int) -> dict[str, int]:
                return {"line": text.count("\n", 0, offset), "character": offset - (text.rfind("\n", 0, offset) + 1)}

            # a keystroke: a blank typed (and removed) inside the option's first state
            at = text.index("state ") + len("state ")
            diagnostics: list[float] = []
            completion: list[float] = []
            general: list[float] = []
            for n in range(args.keystrokes):
                edited = text[:at] + " " + text[at:] if n % 2 == 0 else text
                client.drain()
                t0 = time.perf_counter()
                client.change(path, edited, n + 2)
                client.wait_diagnostics(path)
                diagnostics.append(time.perf_counter() - t0)
                # the positions move one to the right when the blank is in
                shift = 1 if n % 2 == 0 else 0
                for offset, times in ((call, completion), (general_at, general)):
                    t0 = time.perf_counter()
                    result = client.request(
                        "textDocument/completion",
                        {
                            "textDocument": {"uri": uri(path)},
                            "position": position(offset + (shift if at <= offset else 0)),
                        },
                    )
                    times.append(time.perf_counter() - t0)
                    assert result["items"], "completion found nothing"
                    if times is completion:
                        assert all(i["kind"] == 10 for i in result["items"]), "not the call's parameters"
        finally:
            client.close()
        # the same keystroke in process: what each incremental layer costs
        project = Project(str(agents))
        started = time.perf_counter()
        project.analyze()
        first = time.perf_counter() - started
        stages: list[dict[str, float]] = []
        rechecked = 0
        for n in range(args.keystrokes):
            project.set_text(str(path), text[:at] + " " + text[at:] if n % 2 == 0 else text)
            analysis = project.analyze()
            stages.append(analysis.timings)
            rechecked = max(rechecked, analysis.rechecked)

    def show(name: str, values: list[float], goal: float) -> bool:
        median = statistics.median(values)
        p90 = sorted(values)[int(len(values) * 0.9) - 1]
        ok = median < goal
        print(
            f"{name:<24} median {median * 1000:7.1f} ms  p90 {p90 * 1000:7.1f} ms  goal {goal * 1000:.0f} ms  "
            f"{'ok' if ok else 'MISSED'}  ({median / full:.2f} of a full compile)"
        )
        return ok

    print(f"behavior set: {args.options} options, {files} files; {len(compilation.diagnostics)} diagnostics")
    print(f"full compile (in process): {full * 1000:.1f} ms; the server's first analysis {first * 1000:.1f} ms")
    medians = {k: statistics.median(s[k] for s in stages) * 1000 for k in stages[0]}
    print(
        "a keystroke in process: "
        + ", ".join(f"{k} {v:.1f} ms" for k, v in medians.items())
        + f" (at most {rechecked} option rechecked)"
    )
    ok = show("diagnostics/keystroke", diagnostics, DIAGNOSTICS_GOAL)
    ok = show("completion (call)", completion, COMPLETION_GOAL) and ok
    ok = show("completion (everything)", general, COMPLETION_GOAL) and ok
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
