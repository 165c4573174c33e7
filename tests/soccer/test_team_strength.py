"""The example team beats the chase team: 10 seeded matches of 2 x 150 s, two processes.

This is the slowest test of the suite (about a minute and a half on two cores): it is the one
that says the XABSL team really plays football rather than only running.
"""

from __future__ import annotations

from multiprocessing import get_context

from xabsl_studio.examples.soccer.run import play_match

SEEDS = range(10)


def _match(seed: int) -> tuple[int, tuple[int, int], list[str]]:
    report = play_match(seed, half_duration_s=150.0)
    return seed, report.score, report.faults


def test_the_example_team_beats_the_chase_team():
    # "spawn" would re-import everything per worker; "fork" shares the already compiled modules.
    with get_context("fork").Pool(2) as pool:
        results = pool.map(_match, SEEDS)
    for seed, (home, away), faults in results:
        print(f"seed {seed}: {home} : {away} {faults or ''}")
    wins = sum(home > away for _, (home, away), _ in results)
    goals_for = sum(home for _, (home, _), _ in results)
    goals_against = sum(away for _, (_, away), _ in results)
    print(f"wins {wins}/10, goals {goals_for} : {goals_against}")
    assert all(not faults for _, _, faults in results)
    assert wins >= 8
    assert goals_for - goals_against >= 10
