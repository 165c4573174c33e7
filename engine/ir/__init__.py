"""The checked program as plain typed data; see :mod:`xabsl_studio.engine.ir.model`."""

from xabsl_studio.engine.ir.model import *  # noqa: F403
