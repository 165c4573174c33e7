"""NaoTH robots, simulators and game logs (docs/naoth.md).

* :mod:`.messages`: the debug messages (protobuf classes built from the project's definitions);
* :mod:`.join`: a robot's behavior messages joined by name with our compile of the same sources;
* :mod:`.log`: reading game logs (records of frame, name, size, payload);
* :mod:`.importer`: a game log as a recording (``xabsl import naoth``).

The debug-port client that attaches a studio to a robot is the server's
(``xabsl_studio.server.protocol.naoth``, ``xabsl_studio.server.session.naoth``).
"""
