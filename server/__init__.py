"""The studio server: a live simulation session over FastAPI and websockets (docs/protocol.md).

One module per concern:

* ``protocol``  message types, the schema version, close codes, limits (what the UI codes against)
* ``examples``  the world plug-in loader: from ``xabsl serve PATH`` to an ``xabsl_studio.engine.host.Example``
* ``bench_world`` the bench world, for behaviors without a world of their own
* ``worker``    the simulation process: world, engines, commands, one sample per tick
* ``channel``   the non-blocking pipe between the server and the simulation process
* ``session``   the server's end of it: starts, restarts and stops the process, records frames
* ``frames``    per-tick frames: sampling engines, compact encoding, the ring buffer, deltas
* ``clients``   one websocket client: state, latest-frame slot, bounded control queue, sender
* ``files``     behavior files: confinement, versions, atomic writes
* ``graphs``    option-graph and state-machine SVGs cached by content hash
* ``security``  token, origin and host checks, body size limits
* ``app``       FastAPI wiring of all of the above
* ``cli``       ``xabsl serve``
"""
