"""A studio session (server process): the live session, replays and forks, with their frames and history."""
