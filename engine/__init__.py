"""xabsl-studio engine: the platform-independent half of the product.

The pipeline reads top to bottom in the folder names:

* ``xabsl_studio.engine.lang``     source files -> tokens -> AST -> checked program + diagnostics
* ``xabsl_studio.engine.ir``       the checked program as plain typed data (the hub everything else reads)
* ``xabsl_studio.engine.emit``     IR -> intermediate code, JSON for the UI, DOT
* ``xabsl_studio.engine.codegen``  IR -> Python source, compiled once (the fast path)
* ``xabsl_studio.engine.runtime``  the Engine: bindings, tick, activation tree, debug interface
* ``xabsl_studio.engine.host``     the contract a simulated world fulfils
* ``xabsl_studio.engine.worlds``   the world plug-in loader and the bench world

Tools over it: ``trace``, ``record``, ``profile``, ``docs``, ``testing`` (behavior tests), ``cli``.

Nothing here imports pymunk, the web server or an example world.
"""
