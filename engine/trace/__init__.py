"""Activation logs: the conformance trace host and runner (:mod:`xabsl_studio.engine.trace.conformance`)."""
