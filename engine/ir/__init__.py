"""The checked program as plain typed data; see :mod:`engine.ir.model`."""

from engine.ir.model import *  # noqa: F403
