"""One broken snippet per diagnostic code: each asserts the file, line, column and code.

The table covers every code of :data:`xabsl_studio.engine.lang.diagnostics.CODES`, so a new code without a
test fails ``test_every_code_has_a_case``.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from xabsl_studio.engine.lang import Compilation
from xabsl_studio.engine.lang.diagnostics import CODES, Severity

DEFS = """namespace defs("Definitions") {
  enum color { red, green };
  enum level { low, high };
  enum color input light;
  enum level input lvl;
  float input x;
  bool input flag;
  float input f ( float a; float b; );
  float output out;
  bool output flag_out;
  enum color output color_out;
  const k = 3;
}
"""
SKILLS = 'namespace skills("Skills") {\n  behavior stand {\n    float effort;\n  }\n}\n'


def option_file(name: str, body: str, params: str = "", include: str = "skills") -> str:
    return f'include "defs.xabsl";\ninclude "{include}.xabsl";\noption {name} {{\n{params}{body}}}\n'


def state(action: str = "", decision: str = "") -> str:
    decision_block = f"    decision {{\n      {decision}\n    }}\n" if decision else ""
    return f"  initial state s {{\n{decision_block}    action {{\n      {action}\n    }}\n  }}\n"


def agents(*options: str, includes: str = "") -> str:
    lines = [f'include "{o}.xabsl";' for o in options]
    return includes + "\n".join(lines) + '\nagent a("A", ' + options[0] + ");\n"


#: code -> (files, file of the diagnostic, line, column); column None where it depends on the
#: interpreter's stack (where the recursion limit strikes inside 4000 nested parentheses)
CASES: dict[str, tuple[dict[str, str], str, int, int | None]] = {
    "illegal-character": ({"o.xabsl": option_file("o", state("out = x $ 1;"))}, "o.xabsl", 6, 15),
    "unterminated-comment": ({"o.xabsl": "option o {\n  /* open\n"}, "o.xabsl", 2, 3),
    "syntax-error": ({"o.xabsl": option_file("o", state("out = ;"))}, "o.xabsl", 6, 13),
    "unexpected-end-of-file": ({"o.xabsl": "option o {\n  initial state s {"}, "o.xabsl", 2, 20),
    "nesting-too-deep": (
        {"o.xabsl": option_file("o", state("out = " + "(" * 4000 + "1" + ")" * 4000 + ";"))},
        "o.xabsl",
        6,
        None,
    ),
    "missing-include-file": ({"o.xabsl": 'include "defs.xabsl";\ninclude "gone.xabsl";\n'}, "o.xabsl", 2, 1),
    "include-twice": ({"o.xabsl": 'include "defs.xabsl";\ninclude "./defs.xabsl";\n'}, "o.xabsl", 2, 1),
    "unreadable-file": ({"o.xabsl/x": ""}, "o.xabsl", 0, 0),
    "naming": ({"o.xabsl": option_file("other", state())}, "o.xabsl", 3, 8),
    "empty-namespace": ({"e.xabsl": 'namespace e("E") {\n}\n'}, "e.xabsl", 1, 11),
    "namespace-separation": (
        {"n.xabsl": 'namespace n("N") {\n  float input y;\n  behavior b { }\n}\n'},
        "n.xabsl",
        1,
        11,
    ),
    "no-matching-symbol": ({"o.xabsl": option_file("o", state("out = x + distance;"))}, "o.xabsl", 6, 17),
    "multiple-matching-symbols": (
        {"o.xabsl": option_file("o", state("stand();"), include="stand"), "stand.xabsl": option_file("stand", state())},
        "o.xabsl",
        6,
        7,
    ),
    "duplicate-definition": (
        {"n.xabsl": 'namespace n("N") {\n  float input y;\n  float input y;\n}\n'},
        "n.xabsl",
        3,
        15,
    ),
    "parameter-set-twice": ({"o.xabsl": option_file("o", state("out = f(a = 1, a = 2);"))}, "o.xabsl", 6, 22),
    "parameter-missing": ({"o.xabsl": option_file("o", state("out = f(a = 1);"))}, "o.xabsl", 6, 13),
    "unknown-parameter": ({"o.xabsl": option_file("o", state("out = f(c = 1, a = 1, b = 2);"))}, "o.xabsl", 6, 15),
    "unknown-state": (
        {"o.xabsl": option_file("o", state("", "if (flag) goto nowhere;\n      else stay;"))},
        "o.xabsl",
        6,
        22,
    ),
    "unknown-option": ({"agents.xabsl": 'agent a("A", nothing);\n'}, "agents.xabsl", 1, 14),
    "unknown-enum": ({"n.xabsl": 'namespace n("N") {\n  enum shade input s;\n}\n'}, "n.xabsl", 2, 8),
    "missing-initial-state": ({"o.xabsl": option_file("o", "  state s {\n    action { }\n  }\n")}, "o.xabsl", 3, 8),
    "multiple-initial-states": (
        {"o.xabsl": option_file("o", state() + "  initial state t {\n    action { }\n  }\n")},
        "o.xabsl",
        9,
        17,
    ),
    "range-on-non-decimal": ({"n.xabsl": 'namespace n("N") {\n  bool input b [0..1];\n}\n'}, "n.xabsl", 2, 16),
    "parameters-on-non-input": (
        {"n.xabsl": 'namespace n("N") {\n  float output g ( float p; );\n}\n'},
        "n.xabsl",
        2,
        16,
    ),
    "enum-io": ({"n.xabsl": 'namespace n("N") {\n  enum e output { a };\n}\n'}, "n.xabsl", 2, 10),
    "not-assignable": ({"o.xabsl": option_file("o", state("x = 1;"))}, "o.xabsl", 6, 7),
    "not-callable": ({"o.xabsl": option_file("o", state("out = stand();"))}, "o.xabsl", 6, 13),
    "type-mismatch": ({"o.xabsl": option_file("o", state("flag_out = flag && x;"))}, "o.xabsl", 6, 23),
    "mismatching-domain": ({"o.xabsl": option_file("o", state("flag_out = light == lvl;"))}, "o.xabsl", 6, 24),
    "boolean-conditional": ({"o.xabsl": option_file("o", state("flag_out = flag ? true : false;"))}, "o.xabsl", 6, 23),
    "else-without-common-decision": ({"o.xabsl": option_file("o", state("", "else stay;"))}, "o.xabsl", 5, 5),
    "decision-must-start-with-else": (
        {
            "o.xabsl": option_file(
                "o",
                "  common decision {\n    if (flag) goto s;\n  }\n" + state("", "if (flag) stay;\n      else stay;"),
            )
        },
        "o.xabsl",
        8,
        5,
    ),
    "option-graph-cycle": (
        {"o.xabsl": option_file("o", state("p();"), include="p"), "p.xabsl": option_file("p", state("o();"))},
        "p.xabsl",
        6,
        7,
    ),
    "unreachable-option": (
        {
            "agents.xabsl": agents("o", "p", includes='include "defs.xabsl";\ninclude "skills.xabsl";\n'),
            "o.xabsl": option_file(
                "o",
                state(
                    "stand(effort = k); out = x; flag_out = flag; "
                    "color_out = light == red && lvl == low && f(a = 1, b = 2) > 0 "
                    "? green : red;"
                ),
            ),
            "p.xabsl": option_file("p", state()),
        },
        "p.xabsl",
        3,
        8,
    ),
    "unreachable-state": (
        {"o.xabsl": option_file("o", state() + "  state t {\n    action { }\n  }\n")},
        "o.xabsl",
        9,
        9,
    ),
    "unused-symbol": (
        {
            "agents.xabsl": agents("o", includes='include "defs.xabsl";\ninclude "skills.xabsl";\n'),
            "o.xabsl": option_file("o", state("stand(effort = k); out = x; flag_out = flag;")),
        },
        "defs.xabsl",
        4,
        20,
    ),
    "unused-behavior": (
        {
            "agents.xabsl": agents("o", includes='include "defs.xabsl";\ninclude "skills.xabsl";\n'),
            "o.xabsl": option_file("o", state("out = x;")),
        },
        "skills.xabsl",
        2,
        12,
    ),
}


def test_every_code_has_a_case() -> None:
    assert set(CASES) == set(CODES)


@pytest.mark.parametrize("code", sorted(CASES))
def test_diagnostic(code: str, compile_sources: Callable[..., Compilation]) -> None:
    files, file, line, col = CASES[code]
    sources = {"defs.xabsl": DEFS, "skills.xabsl": SKILLS, **files}
    main = next(iter(files))
    if code == "unreadable-file":  # a folder where a file should be
        main = "o.xabsl"
    compilation = compile_sources(sources, main=main)
    print("\n".join(d.format() for d in compilation.diagnostics))
    found = [d for d in compilation.diagnostics if d.code == code]
    assert found, f"no {code} diagnostic"
    d = found[0]
    assert d.file == file
    where = (d.span.line, d.span.col) if d.span else (0, 0)
    assert where == (line, col if col is not None else where[1])
    if CODES[code][0] is Severity.ERROR:
        assert compilation.program is None
    else:
        assert not d.is_error


def test_one_mistake_gives_one_error(compile_sources: Callable[..., Compilation]) -> None:
    compilation = compile_sources(
        {
            "o.xabsl": option_file("o", state("flag_out = (x + nothing) > 2 && flag;")),
            "defs.xabsl": DEFS,
            "skills.xabsl": SKILLS,
        }
    )
    assert [d.code for d in compilation.errors] == ["no-matching-symbol"]


def test_all_errors_of_all_files_are_reported(compile_sources: Callable[..., Compilation]) -> None:
    compilation = compile_sources(
        {
            "agents.xabsl": 'include "defs.xabsl";\ninclude "skills.xabsl";\ninclude "o.xabsl";\n'
            'include "p.xabsl";\nagent a("A", o);\n',
            "defs.xabsl": DEFS,
            "skills.xabsl": SKILLS,
            "o.xabsl": option_file("o", state("out = ;\n p();") + "  state t {\n    action { out = nope; }\n  }\n"),
            "p.xabsl": option_file("p", state("flag_out = 1;")),
        }
    )
    errors = [(d.file, d.span.line, d.code) for d in compilation.errors]
    assert errors == [("o.xabsl", 6, "syntax-error"), ("p.xabsl", 6, "type-mismatch")]
