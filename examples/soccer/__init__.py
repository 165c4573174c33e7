"""Robot soccer: an SPL-like match in a pymunk world, for XABSL team behaviors.

One concern per module:

* ``units``      the only place where behavior units (mm, degrees, ms) meet physics units (m, rad, s)
* ``field``      field geometry (SPL-like 9 m x 6 m), team frames, the static scene
* ``physics``    the pymunk space: ball with rolling friction, robot bodies, posts, nets, walls
* ``robot``      the walking robot: motion requests, speed/acceleration limits, walk_to, kicks
* ``game``       the referee: game states, halves, goals, outs, kick-off placement
* ``perception`` each robot's world model: own pose, ball, opponents, team messages
* ``world``      ``SoccerWorld``, the host contract (``xabsl_studio.engine.host.World``) over all of the above
* ``scripted``   a placeholder "chase the ball" controller for tests and benchmarks only

Start with ``world.build_world(seed)``.
"""
