"""IR -> Python source, compiled once per program: the fast path the engine runs.

:mod:`xabsl_studio.engine.codegen.support` holds the arithmetic rules of §2.6 and §2.8 that generated code
calls; :mod:`xabsl_studio.engine.codegen.layout` describes where the engine keeps each value;
:mod:`xabsl_studio.engine.codegen.python` writes and compiles the source.
"""
