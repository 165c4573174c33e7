"""Comparing two versions of a behavior set: what changed in the IR (``xabsl diff``).

Two checked programs (:class:`xabsl_studio.engine.ir.Program`, built by ``compile_file``) are
compared as data, never as text, so a reformatted file is no change and a moved state is none
either (docs/compare.md):

* :mod:`xabsl_studio.engine.compare.structure`  :func:`diff_programs`: the changes, each once, with
  the file:line of both sides
* :mod:`xabsl_studio.engine.compare.graphs`     the docs' option graph and state machines with the
  changes marked (CSS classes on the drawings' own element ids)
* :mod:`xabsl_studio.engine.compare.report`     the changes as the JSON document, text lines and
  one self-contained HTML page

The behavioral side (what a change did on the field) is :mod:`xabsl_studio.engine.profile.against`.
"""

from xabsl_studio.engine.compare.structure import Change, Detail, StructuralDiff, Where, diff_programs

__all__ = ["Change", "Detail", "StructuralDiff", "Where", "diff_programs"]
