"""Structural rules of the code base, checked with ``ast`` (no code is imported or run).

* No module reaches into another module's underscore names: no ``from m import _x``, no
  ``m._x`` on an imported project module, no ``obj._x`` for an attribute the module does not
  define itself (a module's own names, ``self._x`` and ``cls._x`` are fine; dunders are public).
  The rule is about the project's owners: the private names of the standard library and of
  third-party packages are outside it (``argparse._SubParsersAction`` is what argparse's typing
  offers); uses of a third party's private attribute are listed in :data:`THIRD_PARTY`.
* No import cycles among the project's modules, counting every import: module level,
  ``TYPE_CHECKING`` blocks (a cycle for the type checker is still a cycle between owners) and
  imports inside functions (a lazy import that closes a circle only hides it). Lazy imports that
  close none stay allowed: they keep ``xabsl --help`` and the server process light.
* Imports point down the layers (:data:`LAYERS`, :data:`ENGINE_LAYERS`): the server's four along
  its process line, the language server and the examples beside it on the engine, and the
  engine's own stages.
* Every exception class derives from ``XabslError`` (engine/errors.py draws the tree).
* The project is imported by one name of its own, ``xabsl_studio`` (xabsl_studio/__init__.py).
"""

from __future__ import annotations

import ast
import builtins
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: the import package: its entries link to the repository's folders (xabsl_studio/__init__.py)
PACKAGE = "xabsl_studio"
CHECKED = ("engine", "server", "examples", "lsp")

#: Underscore attributes that are public API of the standard library (namedtuple's methods).
PUBLIC_UNDERSCORE = frozenset({"_replace", "_asdict", "_fields", "_make", "_field_defaults"})

#: (file, attribute) -> why a module reads a private attribute of a third-party object.
THIRD_PARTY = {
    (
        "examples/soccer/physics.py",
        "_body",
    ): "pymunk's cffi body pointer (pinned 7.x, checked by tests/soccer/test_physics.py)",
}


def module_name(path: Path, root: Path = ROOT) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def python_files(*packages: str) -> Iterator[Path]:
    for package in packages:
        yield from sorted((ROOT / PACKAGE / package).rglob("*.py"))


def ours(module: str) -> bool:
    return module.split(".")[0] == PACKAGE


def private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def own_names(tree: ast.Module) -> set[str]:
    """Every name the module defines: functions, classes, assigned names and attributes."""
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names.add(node.name)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
            names.add(node.attr)
        elif isinstance(node, ast.arg):
            names.add(node.arg)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
    return names


def resolve(module: str, is_package: bool, node: ast.ImportFrom) -> str:
    """The absolute module an ``ImportFrom`` names (relative imports resolved)."""
    if not node.level:
        return node.module or ""
    base = module.split(".")
    if not is_package:
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join([*base, node.module] if node.module else base)


def underscore_violations(path: Path, root: Path = ROOT) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    module = module_name(path, root)
    is_package = path.name == "__init__.py"
    own = own_names(tree)
    imported_modules: set[str] = set()  # project modules bound to a name in this module
    foreign_modules: set[str] = set()  # other modules bound to a name (their privates are theirs)
    found: list[str] = []
    where = path.resolve().relative_to(root.resolve())  # the repository's path, not the link's
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            source = resolve(module, is_package, node)
            project = ours(source)
            for alias in node.names:
                if project and private(alias.name) and source != module:
                    found.append(f"{where}:{node.lineno}: imports {alias.name} from {source}")
                (imported_modules if project else foreign_modules).add(alias.asname or alias.name)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                project = ours(alias.name)
                if project and any(private(part) for part in alias.name.split(".")):
                    found.append(f"{where}:{node.lineno}: imports private module {alias.name}")
                (imported_modules if project else foreign_modules).add(alias.asname or alias.name.split(".")[0])
    for node in ast.walk(tree):
        if not isinstance(node, ast.Attribute) or not private(node.attr) or node.attr in PUBLIC_UNDERSCORE:
            continue
        owner = node.value
        if isinstance(owner, ast.Name) and owner.id in ("self", "cls"):
            continue
        if isinstance(owner, ast.Name) and owner.id in imported_modules:
            found.append(f"{where}:{node.lineno}: {owner.id}.{node.attr}")
        elif isinstance(owner, ast.Name) and owner.id in foreign_modules:
            continue
        elif node.attr not in own and (str(where), node.attr) not in THIRD_PARTY:
            found.append(f"{where}:{node.lineno}: {ast.unparse(node)} (not a name of this module)")
    return found


def test_no_cross_module_underscore_names() -> None:
    found = [v for path in python_files(*CHECKED) for v in underscore_violations(path)]
    assert not found, "cross-module underscore access:\n" + "\n".join(found)


def import_graph(*packages: str, local: bool = False) -> dict[str, set[str]]:
    """Module -> the project modules it imports, over ``packages``.

    Module-level imports and ``TYPE_CHECKING`` blocks always count; ``local`` adds the imports
    inside functions. An import of ``pkg.mod.name`` counts as an edge to the longest module prefix.
    """
    modules = {module_name(path): path for path in python_files(*packages)}
    graph: dict[str, set[str]] = {}
    for module, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        is_package = path.name == "__init__.py"
        edges: set[str] = set()
        nodes = ast.walk(tree) if local else module_level(tree.body)
        for node in nodes:
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                source = resolve(module, is_package, node)
                # ``from pkg import mod`` imports the submodule; ``from mod import name`` the module.
                targets = [f"{source}.{a.name}" if f"{source}.{a.name}" in modules else source for a in node.names]
            else:
                continue
            for target in targets:
                while target and target not in modules:
                    target = target.rpartition(".")[0]
                if target and target != module:
                    edges.add(target)
        graph[module] = edges
    return graph


def module_level(body: list[ast.stmt]) -> Iterator[ast.stmt]:
    """The statements run at import time (into ``if``/``try`` blocks, not into functions or classes)."""
    for node in body:
        yield node
        if isinstance(node, ast.If | ast.Try):
            yield from module_level(node.body)
            yield from module_level(node.orelse)
            if isinstance(node, ast.Try):
                for handler in node.handlers:
                    yield from module_level(handler.body)
                yield from module_level(node.finalbody)


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Every strongly connected component with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_import_cycles_anywhere_counting_imports_inside_functions() -> None:
    found = cycles(import_graph(*CHECKED, local=True))
    assert not found, "import cycles:\n" + "\n".join(" <-> ".join(c) for c in found)


#: The project's layers and what each may import (its own layer and the ones named). The server's
#: run along its process line (docs/architecture.md); the engine knows none of them.
LAYERS: dict[str, frozenset[str]] = {
    "engine": frozenset(),
    "examples": frozenset({"engine"}),
    # the language server shares the studio's wire limits (message sizes, connection caps)
    "lsp": frozenset({"engine", "server.protocol"}),
    "server.protocol": frozenset({"engine"}),
    # `xabsl mcp`: the engine's answers to an assistant, its own process like the language server
    "server.mcp": frozenset({"engine"}),
    "server.simulation": frozenset({"engine", "server.protocol"}),
    "server.session": frozenset({"engine", "server.protocol", "server.simulation"}),
    "server.api": frozenset({"engine", "lsp", "server.protocol", "server.simulation", "server.session"}),
    "server.cli": frozenset({"engine", "lsp", "server.protocol", "server.simulation", "server.session", "server.api"}),
    "server": frozenset(),
}

#: The engine's stages, lowest first: a module imports only its own stage's and lower ones.
ENGINE_LAYERS: tuple[frozenset[str], ...] = (
    frozenset({"types", "errors", "recursion", ""}),
    frozenset({"files", "ir"}),
    frozenset({"lang", "emit", "codegen", "dynamics", "planning"}),
    frozenset({"runtime"}),
    frozenset({"host", "trace"}),
    frozenset({"record", "docs", "worlds"}),
    frozenset({"profile", "testing", "compare", "query", "naoth"}),
    frozenset({"cli"}),
)


def layer(module: str) -> str:
    """The :data:`LAYERS` key of a project module (``xabsl_studio.server.api.app`` -> ``server.api``)."""
    parts = module.split(".")[1:]
    if parts[0] == "server" and len(parts) > 1:
        return ".".join(parts[:2])
    return parts[0]


def engine_stage(module: str) -> int:
    parts = module.split(".")
    name = parts[2] if len(parts) > 2 else ""
    return next(i for i, stage in enumerate(ENGINE_LAYERS) if name in stage)


def layer_violations(graph: dict[str, set[str]]) -> list[str]:
    found = []
    for module, targets in sorted(graph.items()):
        for target in sorted(targets):
            here, there = layer(module), layer(target)
            if here != there and there not in LAYERS[here]:
                found.append(f"{module} -> {target} ({here} may not import {there})")
            elif here == there == "engine" and engine_stage(target) > engine_stage(module):
                found.append(f"{module} -> {target} (a lower engine stage imports a higher one)")
    return found


def test_imports_point_down_the_layers() -> None:
    graph = import_graph(*CHECKED, local=True)
    assert set(map(layer, graph)) <= set(LAYERS), set(map(layer, graph)) - set(LAYERS)
    found = layer_violations(graph)
    assert not found, "imports against the layers:\n" + "\n".join(found)


def test_the_layer_rule_catches() -> None:
    assert layer_violations({"xabsl_studio.engine.ir": {"xabsl_studio.server.api.app"}})
    assert layer_violations({"xabsl_studio.server.session.live": {"xabsl_studio.server.api.app"}})
    assert layer_violations({"xabsl_studio.server.api.app": {"xabsl_studio.examples.soccer"}})
    assert layer_violations({"xabsl_studio.engine.runtime.engine": {"xabsl_studio.engine.record.reader"}})
    assert not layer_violations({"xabsl_studio.server.api.app": {"xabsl_studio.server.session.live"}})


# -- one exception tree ----------------------------------------------------------------------------

#: the builtin exception classes a project class may name as a base
BUILTIN_EXCEPTIONS = frozenset(
    name for name, value in vars(builtins).items() if isinstance(value, type) and issubclass(value, BaseException)
)


def exception_classes(paths: list[Path], root: Path = ROOT) -> dict[str, tuple[str, list[str]]]:
    """Class name -> (where, base names) of every class in ``paths``."""
    classes: dict[str, tuple[str, list[str]]] = {}
    for path in paths:
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef):
                bases = [
                    b.id if isinstance(b, ast.Name) else b.attr if isinstance(b, ast.Attribute) else ""
                    for b in node.bases
                ]
                classes[node.name] = (f"{path.resolve().relative_to(root.resolve())}:{node.lineno}", bases)
    return classes


def outside_the_tree(classes: dict[str, tuple[str, list[str]]]) -> list[str]:
    """The exception classes that do not derive from ``XabslError``."""

    def derives(name: str, goal: str, seen: frozenset[str] = frozenset()) -> bool:
        if name == goal:
            return True
        if name in seen or name not in classes:
            return False
        return any(derives(base, goal, seen | {name}) for base in classes[name][1])

    def is_exception(name: str, seen: frozenset[str] = frozenset()) -> bool:
        if name in BUILTIN_EXCEPTIONS:
            return True
        if name in seen or name not in classes:
            return False
        return any(is_exception(base, seen | {name}) for base in classes[name][1])

    return sorted(
        f"{where}: {name}({', '.join(bases)})"
        for name, (where, bases) in classes.items()
        if name != "XabslError" and is_exception(name) and not derives(name, "XabslError")
    )


def test_every_exception_class_derives_from_xabsl_error() -> None:
    found = outside_the_tree(exception_classes(list(python_files(*CHECKED))))
    assert not found, "exception classes outside the XabslError tree:\n" + "\n".join(found)


def test_the_exception_rule_catches(tmp_path: Path) -> None:
    source = "class XabslError(Exception): ...\nclass A(XabslError): ...\nclass B(ValueError): ...\nclass C(B): ...\n"
    found = outside_the_tree(exception_classes([write(tmp_path, "m.py", source)], tmp_path))
    assert [line.split(": ", 1)[1] for line in found] == ["B(ValueError)", "C(B)"]


# -- the checks themselves can fail ------------------------------------------------------------------


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize(
    "source",
    [
        "from xabsl_studio.engine.runtime.engine import _helper\n",
        "import xabsl_studio.engine.runtime.engine as e\ne._tick\n",
        "def f(engine):\n    return engine._tick\n",
        "from xabsl_studio.engine.runtime import engine\nengine._tick\n",
        "from xabsl_studio.engine import _private\n",
    ],
)
def test_underscore_rule_catches(source: str, tmp_path: Path) -> None:
    assert underscore_violations(write(tmp_path, "m.py", source), tmp_path)


@pytest.mark.parametrize(
    "source",
    [
        "class A:\n    def __init__(self):\n        self._x = 1\n    def f(self, other):\n        return other._x\n",
        "def _g():\n    pass\nclass B:\n    h = staticmethod(_g)\nB()._g\n",
        "import collections\np = collections.namedtuple('P', 'a')(1)._replace(a=2)\n",
    ],
)
def test_underscore_rule_allows(source: str, tmp_path: Path) -> None:
    assert not underscore_violations(write(tmp_path, "m.py", source), tmp_path)


def test_cycle_finder() -> None:
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


# -- one import name of our own ------------------------------------------------------------------------

#: the repository's folders, imported only as ``xabsl_studio.<folder>`` (xabsl_studio/__init__.py)
FOLDERS = frozenset({"engine", "server", "examples", "lsp"})


def bare_imports(path: Path, root: Path = ROOT) -> list[str]:
    """Imports of a repository folder by its bare name (``import engine``, ``from server.app ...``)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    found: list[str] = []
    for node in ast.walk(tree):
        names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
        if isinstance(node, ast.ImportFrom) and not node.level and node.module:
            names = [node.module]
        found += [f"{path.relative_to(root)}:{node.lineno}: {n}" for n in names if n.split(".")[0] in FOLDERS]
    return found


def test_every_module_imports_the_project_through_its_one_package_name() -> None:
    files = [p for folder in (*FOLDERS, "tests", "benchmarks") for p in sorted((ROOT / folder).rglob("*.py"))]
    found = [v for path in files for v in bare_imports(path)]
    assert not found, "imports by a generic top-level name (use xabsl_studio.<folder>):\n" + "\n".join(found)


@pytest.mark.parametrize("source", ["import engine\n", "from server.app import create_app\n", "import lsp.cli as c\n"])
def test_bare_import_rule_catches(source: str, tmp_path: Path) -> None:
    assert bare_imports(write(tmp_path, "m.py", source), tmp_path)


#: The session kinds the studio's edge must not tell apart by class (it asks the session).
SESSION_KINDS = frozenset({"Session", "ReplaySession", "AttachedSession"})


def session_class_checks(files: list[Path], root: Path = ROOT / PACKAGE) -> list[str]:
    """``isinstance(x, ReplaySession)`` and the like: where the edge branches on a session's class."""
    found = []
    for path in files:
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "isinstance":
                kinds = node.args[1] if len(node.args) == 2 else None
                names = {n.id for n in ast.walk(kinds) if isinstance(n, ast.Name)} if kinds is not None else set()
                if names & SESSION_KINDS:
                    found.append(f"{path.relative_to(root)}:{node.lineno}")
    return found


def test_the_edge_asks_sessions_instead_of_testing_their_class() -> None:
    found = session_class_checks(list(python_files("server/api")))
    assert not found, "server/api branches on a session's class (add to the Session interface):\n" + "\n".join(found)


def test_the_session_class_rule_catches(tmp_path: Path) -> None:
    source = "def f(s):\n    return isinstance(s, ReplaySession | int)\n\ndef g(s):\n    return isinstance(s, int)\n"
    assert session_class_checks([write(tmp_path, "m.py", source)], tmp_path) == ["m.py:2"]
