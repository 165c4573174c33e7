"""The studio fixtures of tests/server (sessions, live servers, websocket clients), for the errands studio tests."""

from tests.server.conftest import client_for, demo_dir, demo_session, live_demo

__all__ = ["client_for", "demo_dir", "demo_session", "live_demo"]
