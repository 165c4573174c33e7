"""Activation logs: the conformance trace host and runner (:mod:`engine.trace.conformance`)."""
