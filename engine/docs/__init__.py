"""HTML documentation of a behavior set, as the original XABSL compiler produced it.

``xabsl docs AGENTS_FILE -o DIR`` and the studio's ``/docs`` both call :func:`generate`: per
agent its option graph, per option a page (doc comment, parameters, state machine, each
state's decision tree and actions, callers), pages for symbols, enumerations, constants and
basic behaviors with who reads, writes and calls them, an index and an offline search box.
Everything comes from the IR and the doc comments it keeps; the pictures are the studio's DOT
(:mod:`xabsl_studio.engine.emit.dot`) laid out by Graphviz.

Modules: :mod:`.xref` (cross references), :mod:`.graphs` (DOT with links, batched ``dot``),
:mod:`.pages` (HTML), :mod:`.assets` (CSS and the search script), :mod:`.site` (the writer);
:mod:`.pictures` draws the same graphs as SVG, PNG or PDF to take away (``xabsl picture``).
"""

from xabsl_studio.engine.docs.graphs import GraphLayoutError
from xabsl_studio.engine.docs.site import DocsResult, build, generate, program_digest, write

__all__ = ["DocsResult", "GraphLayoutError", "build", "generate", "program_digest", "write"]
