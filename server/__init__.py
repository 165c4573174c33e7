"""The studio server, in four layers along its process line (imports point down only).

* ``api``         the HTTP/websocket edge (server process): FastAPI app, clients, security, the
                  routes of files, graphs, docs, profile, recordings and forks
* ``session``     a studio session (server process): the live one and its simulation process's
                  server end, replays, forks started from recordings, frames and the ring,
                  generations, breakpoints, behavior files, the live recording
* ``simulation``  the simulation process: worlds, engines, commands between two ticks, one
                  sample per tick, the run log that forks replay
* ``protocol``    what both processes and the browser speak: message types, limits, the pipe

``cli`` is ``xabsl serve``. The world loader and the bench world are ``xabsl_studio.engine.worlds``
(headless runs, tests and tournaments use them without a server). docs/architecture.md walks it.
"""
