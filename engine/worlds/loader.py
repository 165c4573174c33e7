"""The world plug-in loader: from the path a user names (``xabsl serve PATH``) to an Example.

The server knows no world. It asks :func:`load_example`, which finds the factory that says how to
run ``PATH`` (the contract is :class:`xabsl_studio.engine.host.Example`), in this order:

1. ``--world NAME``: the factory registered as ``NAME`` under the entry-point group
   ``xabsl.worlds`` (``xabsl_studio.engine.host.WORLDS_GROUP``), or a ``module:attribute`` reference;
2. a folder holding ``studio.py``: that module's ``example`` (imported by its package name when
   the folder is an importable package, else from its file, as a package of its own so that it
   may import its siblings relatively);
3. anything else (a behavior folder with ``agents.xabsl``, or an agents file anywhere on disk):
   the bench world (:data:`BENCH_WORLD`).

The factory is called as ``factory(path, **options)``. What it returns is wrapped in a
:class:`WorldPlugin`, which pickles as the way to load it again (path, world, options), so the
simulation process gets the plug-in even when its module was loaded from a file outside any
package, and which adds that module to the forkserver's preload list.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.metadata
import importlib.util
import sys
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

import xabsl_studio
from xabsl_studio.engine.host import (
    STUDIO_FACTORY,
    STUDIO_MODULE,
    WORLDS_GROUP,
    Agent,
    AgentController,
    BehaviorSource,
    Example,
    ExampleError,
    ExampleFactory,
    World,
)
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.runtime import Engine

__all__ = ["BENCH_WORLD", "ExampleError", "WorldPlugin", "load_example", "world_names"]

#: The factory for behaviors that bring no world of their own.
BENCH_WORLD = "xabsl_studio.engine.worlds.bench:example"
#: Worlds known without an installed entry point.
BUILTIN_WORLDS = {"bench": BENCH_WORLD}


class WorldPlugin:
    """An :class:`~xabsl_studio.engine.host.Example` as loaded by :func:`load_example`, picklable by reference.

    Every member of the contract is the plug-in's own; pickling keeps only ``(path, world,
    options)`` and unpickling loads the plug-in again (in the simulation process).
    """

    __slots__ = ("example", "module", "options", "path", "world")

    def __init__(
        self, example: Example, path: Path, world: str | None, options: Mapping[str, Any], module: str | None
    ) -> None:
        self.example = example
        self.path = path
        self.world = world
        self.options = dict(options)
        #: the importable name of the module the factory came from (None: loaded from a file)
        self.module = module

    def __reduce__(self) -> tuple[Any, ...]:
        return (_reload, (str(self.path), self.world, self.options))

    @property
    def name(self) -> str:
        """The plug-in's name."""
        return self.example.name

    @property
    def root(self) -> Path:
        """The folder file paths are relative to."""
        return self.example.root

    @property
    def sources(self) -> Sequence[BehaviorSource]:
        """The behavior sets to compile."""
        return self.example.sources

    @property
    def preload(self) -> Sequence[str]:
        """The plug-in's preload list, plus the factory's module when it is importable by name."""
        own = tuple(self.example.preload)
        return own if self.module is None or self.module in own else (self.module, *own)

    @property
    def behavior_hz(self) -> int:
        """The behavior rate the world is built for."""
        return self.example.behavior_hz

    @property
    def physics_hz(self) -> int:
        """The physics rate the world is built for."""
        return self.example.physics_hz

    def build_world(self, seed: int) -> World:
        """A fresh world of the plug-in."""
        return self.example.build_world(seed)

    def program_key(self, agent: Agent) -> str | None:
        """The behavior set ``agent`` runs."""
        return self.example.program_key(agent)

    def make_controller(self, agent: Agent, program: Program) -> tuple[AgentController, Engine]:
        """The plug-in's controller and engine for ``agent``."""
        return self.example.make_controller(agent, program)


def load_example(path: str | Path, world: str | None = None, **options: Any) -> WorldPlugin:
    """The world plug-in that runs ``path`` (see the module docstring for the order).

    Args:
        path: an example folder (with ``studio.py``), a behavior folder or an agents file.
        world: a world registered under ``xabsl.worlds`` (or ``module:attribute``) to run
            ``path`` in, instead of the one the folder names.
        **options: the factory's options (``robots`` and whatever the plug-in documents).

    Raises:
        ExampleError: no such path, an unknown world, a plug-in that fails to load, or options
            the factory does not take.
    """
    target = Path(path).expanduser().resolve()
    if not target.exists():
        raise ExampleError(f"{path}: no such folder or agents file")
    module_name: str | None
    if world is not None:
        factory, module_name = _named_world(world)
    elif target.is_dir() and (target / f"{STUDIO_MODULE}.py").is_file():
        factory, module_name = _studio_factory(target)
    else:
        factory, module_name = _reference(BENCH_WORLD)
    try:
        example = factory(target, **options)
    except TypeError as error:  # options the factory does not take
        raise ExampleError(f"{path}: {error}") from None
    return WorldPlugin(example, target, world, options, module_name)


def world_names() -> list[str]:
    """The worlds ``--world`` accepts: the built-in ones and every installed entry point."""
    names = set(BUILTIN_WORLDS)
    names.update(ep.name for ep in importlib.metadata.entry_points(group=WORLDS_GROUP))
    return sorted(names)


def _reload(path: str, world: str | None, options: dict[str, Any]) -> WorldPlugin:
    return load_example(path, world, **options)


def _named_world(world: str) -> tuple[ExampleFactory, str | None]:
    for ep in importlib.metadata.entry_points(group=WORLDS_GROUP):
        if ep.name == world:
            return _reference(ep.value)
    if world in BUILTIN_WORLDS:
        return _reference(BUILTIN_WORLDS[world])
    if ":" in world:
        return _reference(world)
    raise ExampleError(f"unknown world {world!r} (known: {', '.join(world_names())}; or module:attribute)")


def _reference(reference: str) -> tuple[ExampleFactory, str]:
    module_name, _, attribute = reference.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ImportError as error:
        raise ExampleError(f"world {reference}: {error}") from None
    return _factory(module, attribute or STUDIO_FACTORY, reference), module_name


def _factory(module: ModuleType, attribute: str, where: str) -> ExampleFactory:
    factory = getattr(module, attribute, None)
    if not callable(factory):
        raise ExampleError(f"{where}: defines no callable {attribute}(path, **options)")
    result: ExampleFactory = factory
    return result


def _studio_factory(folder: Path) -> tuple[ExampleFactory, str | None]:
    file = folder / f"{STUDIO_MODULE}.py"
    package = _package_of(folder)
    if package is not None:
        name = f"{package}.{STUDIO_MODULE}"
        try:
            spec = importlib.util.find_spec(name)
        except ImportError:
            spec = None
        if spec is not None and spec.origin is not None and Path(spec.origin).resolve() == file.resolve():
            return _factory(_import(lambda: importlib.import_module(name), file), STUDIO_FACTORY, str(file)), name
    return _factory(_load_file(folder, file), STUDIO_FACTORY, str(file)), None


def _package_of(folder: Path) -> str | None:
    """The dotted package name of ``folder`` if it and its parents are packages, else None.

    A folder of this repository's checkout (``examples/NAME``) is named as the import package
    maps it (``xabsl_studio.examples.NAME``), never by its folder name: importing it twice under
    two names would make two copies of every class.
    """
    parts: list[str] = []
    current = folder
    while (current / "__init__.py").is_file() and current.name.isidentifier():
        parts.insert(0, current.name)
        current = current.parent
    if parts and parts[0] != xabsl_studio.__name__:
        linked = Path(xabsl_studio.__file__ or "").parent / parts[0]
        if linked.is_dir() and linked.resolve() == (current / parts[0]).resolve():
            parts.insert(0, xabsl_studio.__name__)
    return ".".join(parts) if parts else None


def _load_file(folder: Path, file: Path) -> ModuleType:
    """Import ``file`` as ``<package>.studio``, ``<package>`` a synthetic package over ``folder``."""
    digest = hashlib.sha256(str(folder).encode()).hexdigest()[:10]
    package = f"_xabsl_world_{digest}"
    name = f"{package}.{STUDIO_MODULE}"
    loaded = sys.modules.get(name)
    if loaded is not None:
        return loaded

    def execute() -> ModuleType:
        parent = ModuleType(package)
        parent.__path__ = [str(folder)]
        sys.modules.setdefault(package, parent)
        spec = importlib.util.spec_from_file_location(name, file)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        try:
            spec.loader.exec_module(module)
        except BaseException:
            del sys.modules[name]
            raise
        return module

    return _import(execute, file)


def _import(load: Callable[[], ModuleType], file: Path) -> ModuleType:
    try:
        module = load()
    except ExampleError:
        raise
    except Exception as error:  # a broken plug-in is the user's to fix: say where and why
        raise ExampleError(f"{file}: {type(error).__name__}: {error}") from error
    return module
