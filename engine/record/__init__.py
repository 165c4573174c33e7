"""Recordings: every tick of a run kept in an MCAP file, readable by Foxglove and any MCAP reader.

* :mod:`xabsl_studio.engine.record.schema`   topic names, JSON Schemas, timestamps (the format's one source)
* :mod:`xabsl_studio.engine.record.sampler`  the per-tick read of one engine (the one sampler: the studio's too)
* :mod:`xabsl_studio.engine.record.mcapfile` the MCAP file itself, written from the spec (fast, indexed)
* :mod:`xabsl_studio.engine.record.foxglove` the world as ``foxglove.SceneUpdate`` messages (2D field view)
* :mod:`xabsl_studio.engine.record.encoder`  :class:`RecordingEncoder`: samples -> MCAP messages (no engine needed)
* :mod:`xabsl_studio.engine.record.writer`   :class:`Recorder`: samples a running world, feeds the encoder
* :mod:`xabsl_studio.engine.record.reader`   :class:`Recording`: iterate ticks, seek, rebuild activation trees
* :mod:`xabsl_studio.engine.record.fork`     re-simulate a recorded deterministic run to any tick, switch behavior
* :mod:`xabsl_studio.engine.record.why`      why and why not at a recorded tick, from the recorded reads

Independent of the server: the studio records through the same :class:`Recorder`.
"""

from xabsl_studio.engine.record.encoder import RecordingEncoder
from xabsl_studio.engine.record.reader import AgentTick, Recording, RecordingError, TickView
from xabsl_studio.engine.record.sampler import AgentSample, AgentSampler, ProgramTables
from xabsl_studio.engine.record.writer import Recorder, RecorderStats, RecordingFailed, engines_of

__all__ = [
    "AgentSample",
    "AgentSampler",
    "AgentTick",
    "ProgramTables",
    "Recorder",
    "RecorderStats",
    "Recording",
    "RecordingEncoder",
    "RecordingError",
    "RecordingFailed",
    "TickView",
    "engines_of",
]
