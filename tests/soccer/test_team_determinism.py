"""The example team's matches are pure functions of the seed: score and activation trace."""

from __future__ import annotations

from xabsl_studio.examples.soccer.run import play_match


def test_same_seed_gives_the_same_score_and_activation_trace():
    first = play_match(11, half_duration_s=20.0)
    second = play_match(11, half_duration_s=20.0)
    print(first.as_dict()["score"], first.trace_hash)
    assert first.faults == [] and second.faults == []
    assert first.score == second.score
    assert first.trace_hash == second.trace_hash
    assert first.activations == second.activations


def test_different_seeds_give_different_traces():
    # Noise differs, so the activation traces must differ: the hash really covers the trace.
    assert play_match(11, half_duration_s=10.0).trace_hash != play_match(12, half_duration_s=10.0).trace_hash
