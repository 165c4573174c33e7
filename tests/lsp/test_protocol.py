"""The language server through the real protocol: a client process speaking JSON-RPC over stdio."""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Any

from tests.lsp.client import ROOT, LspClient, position, uri
from xabsl_studio.engine.lang import compile_file


def labels(result: Any) -> list[str]:
    items = result["items"] if isinstance(result, dict) else result
    return [i["label"] for i in items]


def apply_edits(text: str, edits: list[dict[str, Any]]) -> str:
    lines = text.split("\n")
    starts = [0]
    for line in lines:
        starts.append(starts[-1] + len(line) + 1)

    def offset(p: dict[str, int]) -> int:
        return starts[p["line"]] + p["character"]

    for edit in sorted(edits, key=lambda e: offset(e["range"]["start"]), reverse=True):
        a, b = offset(edit["range"]["start"]), offset(edit["range"]["end"])
        text = text[:a] + edit["newText"] + text[b:]
    return text


def test_open_set_publishes_the_compilers_diagnostics(client: LspClient) -> None:
    soccer = ROOT / "examples" / "soccer" / "behavior"
    result = client.initialize(soccer)
    caps = result["capabilities"]
    for feature in (
        "completionProvider",
        "hoverProvider",
        "definitionProvider",
        "referencesProvider",
        "renameProvider",
    ):
        assert caps.get(feature), feature
    agents = soccer / "agents.xabsl"
    client.open(agents)
    published = client.wait_diagnostics(agents)
    compiled = compile_file(str(agents), base=str(soccer))
    expected = sorted(
        (d.code, d.span.line - 1, d.span.col - 1)
        for d in compiled.diagnostics
        if d.span and os.path.realpath(soccer / d.span.file) == os.path.realpath(agents)
    )
    assert (
        sorted((d["code"], d["range"]["start"]["line"], d["range"]["start"]["character"]) for d in published)
        == expected
    )


def test_break_and_fix_a_file(client: LspClient, demo: Path) -> None:
    client.initialize(demo)
    play = demo / "options" / "play.xabsl"
    text = client.open(play)
    assert [d for d in client.wait_diagnostics(play) if d["severity"] == 1] == []
    broken = text.replace("goto chase;", "goto chasee;", 1)
    client.change(play, broken)
    diagnostics = client.wait_diagnostics(play)
    unknown = [d for d in diagnostics if d["code"] == "unknown-state"]
    assert len(unknown) == 1 and "did you mean 'chase'" in unknown[0]["message"]
    assert unknown[0]["range"]["start"] == position(broken, "chasee")
    # the hint is a quick fix that puts the right name in
    actions = client.request(
        "textDocument/codeAction",
        {"textDocument": {"uri": uri(play)}, "range": unknown[0]["range"], "context": {"diagnostics": unknown}},
    )
    assert actions[0]["kind"] == "quickfix"
    fixed = apply_edits(broken, actions[0]["edit"]["changes"][uri(play)])
    assert fixed == text
    client.change(play, fixed, 3)
    assert [d for d in client.wait_diagnostics(play) if d["severity"] == 1] == []
    # a syntax error, then its repair
    client.change(play, text.replace("goto search;", "goto search", 1), 4)
    assert any(d["code"] == "syntax-error" for d in client.wait_diagnostics(play))
    client.change(play, text, 5)
    assert [d for d in client.wait_diagnostics(play) if d["severity"] == 1] == []


def test_an_error_in_another_file_is_published_for_that_file(client: LspClient, demo: Path) -> None:
    client.initialize(demo)
    symbols = demo / "symbols.xabsl"
    approach = demo / "options" / "approach_ball.xabsl"
    text = client.open(symbols)
    client.wait_diagnostics(symbols)
    client.drain()
    client.change(symbols, text.replace("float const kick_distance", "float const kick_dist"))
    found: dict[str, list[dict[str, Any]]] = {}
    play = demo / "options" / "play.xabsl"
    # the first publication for play.xabsl (at open, without errors) may still be on its way
    while not any(d["severity"] == 1 for d in found.get(uri(play), [])):
        message = client.notifications.get(timeout=20)
        if message.get("method") == "textDocument/publishDiagnostics":
            found[message["params"]["uri"]] = message["params"]["diagnostics"]
    assert any("kick_distance" in d["message"] and "did you mean 'kick_dist'" in d["message"] for d in found[uri(play)])
    assert uri(approach) not in found or not any(d["severity"] == 1 for d in found[uri(approach)])


def test_completion(client: LspClient, demo: Path) -> None:
    client.initialize(demo)
    approach = demo / "options" / "approach_ball.xabsl"
    text = client.open(approach)
    client.wait_diagnostics(approach)

    def complete(edited: str, at: dict[str, int]) -> list[dict[str, Any]]:
        client.change(approach, edited)
        result = client.request("textDocument/completion", {"textDocument": {"uri": uri(approach)}, "position": at})
        return list(result["items"])

    # after '@': the option's parameters, with type and unit
    edited = text.replace("ball.distance < @stop_at", "ball.distance < @")
    items = complete(edited, position(edited, "< @", 3))
    assert [i["label"] for i in items] == ["@stop_at"]
    assert "float" in items[0]["detail"] and "mm" in items[0]["detail"]
    assert "Distance at which the robot kicks" in items[0]["documentation"]["value"]
    # state names after goto
    edited = text.replace("goto kicked;", "goto ;")
    items = complete(edited, position(edited, "goto ;", 5))
    assert sorted(i["label"] for i in items) == ["go", "kick", "kicked"]
    # in a call's parameter list: the callee's parameters not given yet
    edited = text.replace("direction = ball.angle);", ");")
    items = complete(edited, position(edited, "max_speed), ", 12))
    assert [i["label"] for i in items] == ["direction"]
    assert items[0]["textEdit"]["newText"] == "direction = "
    # a partly typed symbol: everything named, with symbols' doc comments
    edited = text.replace("if (ball.distance <", "if (ball.d <")
    items = complete(edited, position(edited, "ball.d <", 6))
    distance = next(i for i in items if i["label"] == "ball.distance")
    assert "input float" in distance["detail"] and "mm" in distance["detail"]
    # a short list carries the documentation; a long one gets it on resolve
    assert len(items) <= 60 and "Distance from the robot to the ball" in distance["documentation"]["value"]
    resolved = client.request("completionItem/resolve", {**distance, "documentation": None})
    assert "Distance from the robot to the ball" in resolved["documentation"]["value"]
    assert {"walk", "approach_ball", "kick_distance", "state_time"} <= {i["label"] for i in items}
    # an enum value after '=' to an enum output: its elements first
    edited = text.replace("activity = approaching;", "activity = ;")
    items = complete(edited, position(edited, "activity = ;", 11))
    assert [i["label"] for i in items[:4]] == ["waiting", "searching", "approaching", "kicking"]
    # nothing inside a comment
    items = complete(text, position(text, "Close and", 3))
    assert items == []


def test_completion_after_an_enum_types_dot(client: LspClient, demo: Path) -> None:
    client.initialize(demo)
    play = demo / "options" / "play.xabsl"
    text = client.open(play)
    client.wait_diagnostics(play)
    edited = text.replace("game.state != playing", "game.state != game.state.")
    client.change(play, edited)
    at = position(edited, "!= game.state.", len("!= game.state."))
    result = client.request("textDocument/completion", {"textDocument": {"uri": uri(play)}, "position": at})
    got = labels(result)
    assert got[:5] == [
        "game.state.init",
        "game.state.ready",
        "game.state.set",
        "game.state.playing",
        "game.state.finished",
    ]
    # and after '!=' with the short names
    edited = text.replace("game.state != playing", "game.state != ")
    client.change(play, edited, 3)
    at = position(edited, "game.state != ", len("game.state != "))
    got = labels(client.request("textDocument/completion", {"textDocument": {"uri": uri(play)}, "position": at}))
    assert got[:5] == ["init", "ready", "set", "playing", "finished"]


def test_hover_definition_references(client: LspClient, demo: Path) -> None:
    client.initialize(demo)
    approach = demo / "options" / "approach_ball.xabsl"
    text = client.open(approach)
    client.wait_diagnostics(approach)
    doc = {"uri": uri(approach)}

    hover = client.request(
        "textDocument/hover", {"textDocument": doc, "position": position(text, "ball.distance <", 2)}
    )
    value = hover["contents"]["value"]
    assert "input symbol" in value and "float ball.distance" in value and "[0..10000]" in value and '"mm"' in value
    assert "Distance from the robot to the ball" in value

    hover = client.request("textDocument/hover", {"textDocument": doc, "position": position(text, "walk(", 1)})
    assert "basic behavior" in hover["contents"]["value"] and "speed" in hover["contents"]["value"]

    play = demo / "options" / "play.xabsl"
    play_text = play.read_text()
    client.open(play)
    hover = client.request(
        "textDocument/hover", {"textDocument": {"uri": uri(play)}, "position": position(play_text, "approach_ball(", 2)}
    )
    value = hover["contents"]["value"]
    assert "**option** `approach_ball`" in value and "stop_at" in value and "go (initial)" in value
    assert "slowing down when close" in value

    # definition of a symbol in another file, of a state, of a parameter
    found = client.request(
        "textDocument/definition", {"textDocument": doc, "position": position(text, "ball.distance <", 1)}
    )
    symbols = (demo / "symbols.xabsl").read_text()
    assert found == [
        {
            "uri": uri(demo / "symbols.xabsl"),
            "range": {"start": position(symbols, "ball.distance"), "end": position(symbols, "ball.distance", 13)},
        }
    ]
    found = client.request(
        "textDocument/definition", {"textDocument": doc, "position": position(text, "goto kicked", 6)}
    )
    assert found[0]["range"]["start"] == position(text, "kicked {")
    found = client.request(
        "textDocument/definition", {"textDocument": doc, "position": position(text, "< @stop_at", 3)}
    )
    assert found[0]["range"]["start"] == position(text, "@stop_at [")

    # references of a basic behavior across files, with and without the declaration
    refs = client.request(
        "textDocument/references",
        {"textDocument": doc, "position": position(text, "stand();", 1), "context": {"includeDeclaration": True}},
    )
    files = sorted(Path(r["uri"]).name for r in refs)
    assert files == ["approach_ball.xabsl", "basic_behaviors.xabsl", "play.xabsl", "search_ball.xabsl"] or (
        "basic_behaviors.xabsl" in files and files.count("play.xabsl") == 1
    )
    without = client.request(
        "textDocument/references",
        {"textDocument": doc, "position": position(text, "stand();", 1), "context": {"includeDeclaration": False}},
    )
    assert len(without) == len(refs) - 1


def test_rename_across_files_compiles(client: LspClient, demo: Path) -> None:
    client.initialize(demo)
    approach = demo / "options" / "approach_ball.xabsl"
    text = client.open(approach)
    client.wait_diagnostics(approach)
    doc = {"uri": uri(approach)}
    cases = [
        (position(text, "ball.distance <", 1), "ball.range", "ball.distance"),  # a symbol
        (position(text, "goto kick;", 6), "shoot", "kick;"),  # a state
        (position(text, "@stop_at [", 2), "@halt_at", "stop_at"),  # an option parameter (used as stop_at = in play)
        (position(text, "kick(strength", 1), "boot", "kick(strength"),  # a basic behavior
        (position(text, "approaching;", 2), "closing_in", "approaching"),  # an enum element
        (position(text, "option approach_ball", 8), "go_to_ball", "approach_ball"),  # an option
    ]
    for at, new, old in cases:
        prepared = client.request("textDocument/prepareRename", {"textDocument": doc, "position": at})
        assert prepared is not None, new
        edit = client.request("textDocument/rename", {"textDocument": doc, "position": at, "newName": new})
        changes = edit["changes"]
        overrides = {}
        for file_uri, edits in changes.items():
            path = Path(file_uri.removeprefix("file://"))
            overrides[str(path)] = apply_edits(path.read_text(), edits)
        compiled = compile_file(str(demo / "agents.xabsl"), base=str(demo), overrides=overrides)
        errors = [d.format() for d in compiled.errors]
        assert errors == [], (new, errors)
        bare = new.lstrip("@")
        assert all(e["newText"].endswith(bare) for edits in changes.values() for e in edits), new
        refs = client.request(
            "textDocument/references", {"textDocument": doc, "position": at, "context": {"includeDeclaration": True}}
        )
        assert sum(len(e) for e in changes.values()) == len(refs) >= 2, new
        del old
    # several files change for a symbol
    edit = client.request(
        "textDocument/rename", {"textDocument": doc, "position": cases[0][0], "newName": "ball.range"}
    )
    assert {Path(u).name for u in edit["changes"]} == {"symbols.xabsl", "approach_ball.xabsl"}
    # the parameter's call site in play.xabsl is renamed too
    edit = client.request("textDocument/rename", {"textDocument": doc, "position": cases[2][0], "newName": "halt_at"})
    assert uri(demo / "options" / "play.xabsl") in edit["changes"]


def test_document_and_workspace_symbols(client: LspClient, demo: Path) -> None:
    client.initialize(demo)
    approach = demo / "options" / "approach_ball.xabsl"
    client.open(approach)
    client.wait_diagnostics(approach)
    outline = client.request("textDocument/documentSymbol", {"textDocument": {"uri": uri(approach)}})
    assert [s["name"] for s in outline] == ["approach_ball"]
    assert [c["name"] for c in outline[0]["children"]] == ["@stop_at", "go", "kick", "kicked"]
    found = client.request("workspace/symbol", {"query": "ball."})
    names = {s["name"] for s in found}
    assert {"ball.seen", "ball.distance", "ball.angle", "ball.time_since_seen"} <= names
    assert all("ball." in n for n in names)


def test_semantic_tokens_and_folding(client: LspClient, demo: Path) -> None:
    client.initialize(demo)
    approach = demo / "options" / "approach_ball.xabsl"
    text = client.open(approach)
    client.wait_diagnostics(approach)
    tokens = client.request("textDocument/semanticTokens/full", {"textDocument": {"uri": uri(approach)}})["data"]
    assert len(tokens) % 5 == 0 and tokens
    # decode: absolute positions and types
    line = char = 0
    decoded = []
    for i in range(0, len(tokens), 5):
        dl, dc, length, kind, _ = tokens[i : i + 5]
        line += dl
        char = dc if dl else char + dc
        decoded.append((line, char, length, kind))
    lines = text.split("\n")
    words = {lines[ln][c : c + n]: k for ln, c, n, k in decoded}
    from xabsl_studio.lsp.server import TOKEN_TYPES

    assert TOKEN_TYPES[words["option"]] == "keyword"
    assert TOKEN_TYPES[words["approach_ball"]] == "class"
    assert TOKEN_TYPES[words["@stop_at"]] == "parameter"
    assert TOKEN_TYPES[words["ball.distance"]] == "variable"
    assert TOKEN_TYPES[words["approaching"]] == "enumMember"
    assert TOKEN_TYPES[words["walk"]] == "function"
    folds = client.request("textDocument/foldingRange", {"textDocument": {"uri": uri(approach)}})
    starts = {f["startLine"] for f in folds}
    assert position(text, "option approach_ball")["line"] in starts
    assert position(text, "state kick {")["line"] in starts


def test_a_new_file_joins_when_included(client: LspClient, tmp_path: Path) -> None:
    demo = tmp_path / "demo"
    shutil.copytree(ROOT / "examples" / "demo", demo)
    client.initialize(demo)
    agents = demo / "agents.xabsl"
    text = client.open(agents)
    client.wait_diagnostics(agents)
    client.change(agents, text.replace('include "options/search_ball.xabsl";', 'include "options/nope.xabsl";'))
    assert any(d["code"] == "missing-include-file" for d in client.wait_diagnostics(agents))


def test_every_files_diagnostics_are_the_compilers(client: LspClient, tmp_path: Path) -> None:
    soccer = tmp_path / "behavior"
    shutil.copytree(ROOT / "examples" / "soccer" / "behavior", soccer)
    # a few mistakes in several files, so there is something to compare
    kick = soccer / "options" / "face_ball.xabsl"
    kick.write_text(kick.read_text().replace("goto facing;", "goto facin;"))
    symbols = sorted((soccer / "symbols").glob("*.xabsl"))[0]
    symbols.write_text(symbols.read_text() + "\n")
    client.initialize(soccer)
    agents = soccer / "agents.xabsl"
    client.open(agents)
    compiled = compile_file(str(agents), base=str(soccer))
    by_file: dict[str, list[tuple[str, int, int, str]]] = {}
    for d in compiled.diagnostics:
        assert d.span is not None
        by_file.setdefault(uri(soccer / d.span.file), []).append((d.code, d.span.line - 1, d.span.col - 1, d.message))
    client.wait_diagnostics(agents)
    # every file of the closure is published once at open; wait for the last one
    files = [uri(soccer / f) for f in compiled.files]
    deadline = 0
    while not all(f in client.diagnostics for f in files) and deadline < 200:
        client.request("workspace/symbol", {"query": "zzz"})
        deadline += 1
    assert compiled.errors, "the broken copy has errors"
    for f in files:
        got = sorted(
            (d["code"], d["range"]["start"]["line"], d["range"]["start"]["character"], d["message"])
            for d in client.diagnostics[f]
        )
        assert got == sorted(by_file.get(f, [])), f


def test_a_file_changed_on_disk_is_read_again(client: LspClient, demo: Path) -> None:
    client.initialize(demo)
    play = demo / "options" / "play.xabsl"
    search = demo / "options" / "search_ball.xabsl"
    client.open(play)
    client.wait_diagnostics(play)
    search.write_text(search.read_text().replace("option search_ball", "option search_balls"))
    client.notify("workspace/didChangeWatchedFiles", {"changes": [{"uri": uri(search), "type": 2}]})
    diagnostics = client.wait_diagnostics(play)
    assert any(d["code"] == "no-matching-symbol" and "search_ball" in d["message"] for d in diagnostics)


def test_rename_refuses_a_keyword_and_a_file_outside_a_set_compiles_alone(client: LspClient, tmp_path: Path) -> None:
    lone = tmp_path / "lone.xabsl"
    lone.write_text('namespace lone("x") {\n  float input a;\n  float input b;\n  float input a;\n}\n')
    client.initialize(tmp_path)
    client.open(lone)
    assert [d["code"] for d in client.wait_diagnostics(lone)] == ["duplicate-definition"]
    doc = {"uri": uri(lone)}
    at = {"line": 1, "character": 15}
    try:
        client.request("textDocument/rename", {"textDocument": doc, "position": at, "newName": "state"})
    except RuntimeError as error:
        assert "no valid XABSL name" in str(error)
    else:
        raise AssertionError("a keyword was accepted as a new name")
    edit = client.request("textDocument/rename", {"textDocument": doc, "position": at, "newName": "c"})
    assert edit["changes"][uri(lone)][0]["newText"] == "c"


def test_a_long_completion_list_resolves_its_documentation(client: LspClient) -> None:
    soccer = ROOT / "examples" / "soccer" / "behavior"
    client.initialize(soccer)
    face = soccer / "options" / "face_ball.xabsl"
    text = client.open(face)
    client.wait_diagnostics(face)
    at = position(text, "if (abs", len("if (a"))
    items = client.request("textDocument/completion", {"textDocument": {"uri": uri(face)}, "position": at})["items"]
    assert len(items) > 60
    angle = next(i for i in items if i["label"] == "abs")
    assert not angle.get("documentation")
    resolved = client.request("completionItem/resolve", angle)
    assert "**input symbol**" in resolved["documentation"]["value"] and "abs" in resolved["documentation"]["value"]


def test_renaming_an_enumeration_renames_its_qualified_elements(client: LspClient, demo: Path) -> None:
    play = demo / "options" / "play.xabsl"
    play.write_text(play.read_text().replace("game.state != playing", "game.state != game.state.playing"))
    symbols = demo / "symbols.xabsl"
    text = symbols.read_text()
    client.initialize(demo)
    client.open(symbols)
    client.wait_diagnostics(symbols)
    at = position(text, "enum game.state input", len("enum g"))
    edit = client.request(
        "textDocument/rename", {"textDocument": {"uri": uri(symbols)}, "position": at, "newName": "game.phase"}
    )
    overrides = {
        str(Path(u.removeprefix("file://"))): apply_edits(Path(u.removeprefix("file://")).read_text(), e)
        for u, e in edit["changes"].items()
    }
    assert "game.state != game.phase.playing" in overrides[str(play)]
    assert "enum game.phase { init" in overrides[str(symbols)] and "input game.state;" in overrides[str(symbols)]
    compiled = compile_file(str(demo / "agents.xabsl"), base=str(demo), overrides=overrides)
    assert [d.format() for d in compiled.errors] == []


def test_an_agents_file_of_another_name_is_found(client: LspClient, demo: Path) -> None:
    (demo / "agents.xabsl").rename(demo / "robot.xabsl")
    client.initialize(demo)
    play = demo / "options" / "play.xabsl"
    text = client.open(play)
    # in the set: the symbols resolve (alone, the option would not know 'ball.seen')
    assert [d for d in client.wait_diagnostics(play) if d["severity"] == 1] == []
    found = client.request(
        "textDocument/definition",
        {"textDocument": {"uri": uri(play)}, "position": position(text, "ball.seen", 1)},
    )
    assert found[0]["uri"] == uri(demo / "symbols.xabsl")


def test_incremental_changes_and_positions_after_non_ascii_text(client: LspClient, demo: Path) -> None:
    client.initialize(demo)
    play = demo / "options" / "play.xabsl"
    text = play.read_text()
    # a comment with characters of two and four UTF-16... and UTF-8 widths, on the line of a name
    text = text.replace("else goto search;", "/* é😀 */ else goto search;", 1)
    play.write_text(text)
    client.open(play, text)
    client.wait_diagnostics(play)
    line = position(text, "/* é😀 */ else goto search;")["line"]
    column = text.split("\n")[line].index("search") + 1  # code points: '😀' is one, UTF-16 counts two
    at = {"line": line, "character": column + 1}
    found = client.request("textDocument/definition", {"textDocument": {"uri": uri(play)}, "position": at})
    assert found[0]["range"]["start"] == position(text, "search {")
    refs = client.request(
        "textDocument/references",
        {"textDocument": {"uri": uri(play)}, "position": at, "context": {"includeDeclaration": False}},
    )
    assert {"line": line, "character": column} in [r["range"]["start"] for r in refs]
    # a ranged (incremental) change: 'search' -> 'serch' on that line, in UTF-16 units
    client.notify(
        "textDocument/didChange",
        {
            "textDocument": {"uri": uri(play), "version": 2},
            "contentChanges": [
                {
                    "range": {
                        "start": {"line": line, "character": column + 2},
                        "end": {"line": line, "character": column + 3},
                    },
                    "text": "",
                }
            ],
        },
    )
    diagnostics = client.wait_diagnostics(play)
    unknown = [d for d in diagnostics if d["code"] == "unknown-state"]
    assert unknown and "'serch'" in unknown[0]["message"]
    assert unknown[0]["range"]["start"] == {"line": line, "character": column}


def test_a_client_may_count_in_code_points_or_bytes(demo: Path) -> None:
    play = demo / "options" / "play.xabsl"
    text = play.read_text().replace("else goto search;", "/* é😀 */ else goto search;", 1)
    play.write_text(text)
    line = position(text, "/* é😀 */ else goto search;")["line"]
    points = text.split("\n")[line].index("search")
    for encoding, column in (("utf-32", points), ("utf-8", points + 1 + 3)):  # é: 2 bytes, 😀: 4
        client = LspClient()
        try:
            result = client.initialize(demo, encodings=[encoding])
            assert result["capabilities"]["positionEncoding"] == encoding
            client.open(play, text)
            client.wait_diagnostics(play)
            refs = client.request(
                "textDocument/references",
                {
                    "textDocument": {"uri": uri(play)},
                    "position": {"line": line, "character": column},
                    "context": {"includeDeclaration": False},
                },
            )
            assert {"line": line, "character": column} in [r["range"]["start"] for r in refs], encoding
        finally:
            client.close()


def test_renaming_an_option_moves_its_file_when_the_client_can(client: LspClient, demo: Path) -> None:
    client.initialize(demo, file_renames=True)
    approach = demo / "options" / "approach_ball.xabsl"
    text = client.open(approach)
    client.wait_diagnostics(approach)
    at = position(text, "option approach_ball", len("option a"))
    edit = client.request(
        "textDocument/rename", {"textDocument": {"uri": uri(approach)}, "position": at, "newName": "go_to_ball"}
    )
    assert "changes" not in edit or not edit["changes"]
    operations = edit["documentChanges"]
    assert operations[-1] == {
        "kind": "rename",
        "oldUri": uri(approach),
        "newUri": uri(demo / "options" / "go_to_ball.xabsl"),
    }
    texts = {
        Path(u.removeprefix("file://")): Path(u.removeprefix("file://")).read_text()
        for u in [o["textDocument"]["uri"] for o in operations[:-1]]
    }
    for o in operations[:-1]:
        path = Path(o["textDocument"]["uri"].removeprefix("file://"))
        texts[path] = apply_edits(texts[path], o["edits"])
    agents = texts[demo / "agents.xabsl"]
    assert 'include "options/go_to_ball.xabsl";' in agents
    overrides = {str(p): t for p, t in texts.items() if p != approach}
    overrides[str(demo / "options" / "go_to_ball.xabsl")] = texts[approach]
    approach.unlink()
    compiled = compile_file(str(demo / "agents.xabsl"), base=str(demo), overrides=overrides)
    assert [d.format() for d in compiled.diagnostics if d.is_error or d.code == "naming"] == []
