"""The studio fixtures of tests/server (behavior folders, sessions, live servers), for the world tests."""

from tests.server.conftest import client_for, demo_dir, demo_session, live_demo, soccer_dir, soccer_session

__all__ = ["client_for", "demo_dir", "demo_session", "live_demo", "soccer_dir", "soccer_session"]
