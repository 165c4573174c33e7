import pytest

from xabsl_studio.engine.planning.facts import FactDeriver, FactRule, FactRuleError, Term, errands_rules

DT = 0.02
INIT = {"at-robot a", "at book b", "at mug c"}


def base_signals(**over):
    s = {f"δ_{x}": 0.0 for x in "abc"}
    for o in ("book", "mug"):
        s.update({f"γ_{o}": 0.0, f"alpha.gather_{o}": 0.0, f"alpha.dump_{o}": 0.0, f"g_{o}": 0.0, f"d_{o}": 0.0})
    s.update(over)
    return s


def run(deriver, t0, seconds, **signals):
    """Feed constant signals for `seconds`; return the events and the time reached."""
    events, t = [], t0
    for _ in range(round(seconds / DT)):
        t = round(t + DT, 10)
        events += deriver.update(t, base_signals(**signals))
    return events, t


@pytest.fixture
def deriver():
    return FactDeriver(errands_rules(), facts=frozenset(INIT))


def test_term_parsing():
    t = Term.parse("prev(γ_book) >= 0.8")
    assert (t.signal, t.op, t.value, t.prev) == ("γ_book", ">=", 0.8, True)
    t = Term.parse("alpha.gather_book > .5")
    assert (t.signal, t.op, t.value, t.prev) == ("alpha.gather_book", ">", 0.5, False)
    t = Term.parse("not fact( at-robot  a )")
    assert (t.fact, t.negated) == ("at-robot a", True)


def test_bad_term_named():
    with pytest.raises(FactRuleError, match=r"bad condition term 'γ_book >> 0.8'"):
        Term.parse("γ_book >> 0.8")


def test_unknown_signal_named():
    d = FactDeriver([FactRule.make("p", ["nosuch > 0"])])
    with pytest.raises(FactRuleError, match="reads unknown signal 'nosuch'"):
        d.update(0.0, {"x": 1.0})


def test_rule_validation():
    with pytest.raises(FactRuleError, match="set_dwell must be a finite number >= 0"):
        FactRule.make("p", ["x > 0"], set_dwell=-1)
    with pytest.raises(FactRuleError, match="unknown keys dwell"):
        FactRule.from_dict({"fact": "p", "set_when": ["x > 0"], "dwell": 1})
    with pytest.raises(FactRuleError, match="two rules derive 'p'"):
        FactDeriver([FactRule.make("p", ["x > 0"]), FactRule.make("p", ["x < 0"], name="q")])


def test_from_dict_roundtrip():
    r = FactRule.from_dict({"fact": "p", "set_when": ["x > 0"], "set_dwell": 0.5, "group": "g"})
    assert r.set_dwell == 0.5 and r.group == "g" and r.set_when[0].signal == "x"


def test_at_robot_needs_dwell_and_is_exclusive(deriver):
    both = {"δ_a": 1.0, "δ_c": 1.0}  # near two beacons at once: exclusivity decides
    events, t = run(deriver, 0.0, 0.28, **both)
    assert events == [] and "at-robot c" not in deriver.facts  # 0.28 s < 0.3 s dwell
    events, t = run(deriver, t, 0.04, **both)
    assert "at-robot c" in deriver.facts and "at-robot a" not in deriver.facts
    ev_set = next(e for e in events if e.fact == "at-robot c")
    assert ev_set.value is True
    assert ev_set.cause["phase"] == "set"
    assert ev_set.cause["signals"] == {"δ_c": 1.0}
    assert ev_set.cause["held"] == pytest.approx(0.3)
    ev_ex = next(e for e in events if e.fact == "at-robot a")
    assert ev_ex.value is False and ev_ex.cause == {
        "rule": "at-robot c",
        "phase": "exclusive",
        "by": "at-robot c",
    }


def test_flicker_shorter_than_dwell_ignored(deriver):
    t = 0.0
    for _ in range(10):
        _, t = run(deriver, t, 0.2, **{"δ_b": 1.0, "δ_a": 1.0})
        _, t = run(deriver, t, 0.1, **{"δ_b": 0.0, "δ_a": 1.0})
    assert deriver.facts == INIT


def test_at_robot_clear_after_dwell():
    d = FactDeriver(errands_rules(), facts=frozenset(INIT))
    events, t = run(d, 0.0, 0.5, **{"δ_a": 1.0})
    assert events == []
    events, t = run(d, t, 0.28, **{"δ_a": 0.0})
    assert "at-robot a" in d.facts
    events, t = run(d, t, 0.04, **{"δ_a": 0.0})
    assert "at-robot a" not in d.facts
    assert events[0].cause["phase"] == "cleared" and events[0].cause["signals"] == {"δ_a": 0.0}


def gather(d, t, o="book"):
    """Object in view at γ=0.9 while gathering, then it vanishes into the gripper."""
    on = {f"alpha.gather_{o}": 0.95, f"g_{o}": 0.9}
    _, t = run(d, t, 0.2, **{f"γ_{o}": 0.9}, **on)
    events, t = run(d, t, DT, **{f"γ_{o}": 0.0}, **on)
    return events, t, on


def test_has_robot_tentative_then_confirmed_after_1s():
    d = FactDeriver(errands_rules(), facts=frozenset({"at-robot b", "at book b", "at mug c"}))
    events, t, on = gather(d, 0.0)
    assert [e.cause["phase"] for e in events] == ["tentative"]
    assert events[0].value is False
    assert events[0].cause["signals"]["prev(γ_book)"] == 0.9
    assert d.tentative == {"has-robot book"} and "has-robot book" not in d.facts
    events, t = run(d, t, 0.98, **{"γ_book": 0.0}, **on)
    assert "has-robot book" not in d.facts
    events, t = run(d, t, 0.04, **{"γ_book": 0.0}, **on)
    assert "has-robot book" in d.facts and "at book b" not in d.facts
    confirmed = next(e for e in events if e.fact == "has-robot book")
    assert confirmed.cause["phase"] == "confirmed" and confirmed.cause["held"] == pytest.approx(1.0)
    implied = next(e for e in events if e.fact == "at book b")
    assert implied.cause == {"rule": "has-robot book", "phase": "implied", "by": "has-robot book"}


def test_has_robot_vetoed_when_object_reappears():
    d = FactDeriver(errands_rules(), facts=frozenset(INIT))
    _, t, on = gather(d, 0.0)
    _, t = run(d, t, 0.5, **{"γ_book": 0.0}, **on)
    events, t = run(d, t, DT, **{"γ_book": 0.5}, **on)
    assert [e.cause["phase"] for e in events] == ["retracted"]
    assert d.tentative == set() and "has-robot book" not in d.facts
    _, t = run(d, t, 2.0, **{"γ_book": 0.5}, **on)
    assert "has-robot book" not in d.facts


def test_object_out_of_view_without_gripper_is_not_a_capture():
    d = FactDeriver(errands_rules(), facts=frozenset({"at book b"}))
    _, t = run(d, 0.0, 0.2, **{"γ_book": 0.9, "alpha.gather_book": 0.95, "g_book": 0.2})
    events, t = run(d, t, 2.0, **{"γ_book": 0.0, "alpha.gather_book": 0.95, "g_book": 0.2})
    assert events == []


def test_has_robot_retracted_if_seen_while_gathering():
    d = FactDeriver(errands_rules(), facts=frozenset({"at-robot b", "has-robot book", "at mug c"}))
    events, _ = run(d, 0.0, DT, **{"γ_book": 0.6, "alpha.gather_book": 0.9})
    assert [(e.fact, e.value, e.cause["phase"]) for e in events] == [("has-robot book", False, "cleared")]


def test_dump_at_location_sets_at_and_clears_has_robot():
    d = FactDeriver(errands_rules(), facts=frozenset({"at-robot a", "has-robot book", "has-robot mug"}))
    dump = {"alpha.dump_book": 0.9, "d_book": 0.8, "δ_a": 1.0}
    events, t = run(d, 0.0, 0.28, **dump)
    assert events == []
    events, t = run(d, t, 0.04, **dump)
    assert "at book a" in d.facts and "has-robot book" not in d.facts
    assert "has-robot mug" in d.facts
    at = next(e for e in events if e.fact == "at book a")
    assert at.cause["facts"] == ["fact(at-robot a)"]
    assert at.cause["signals"] == {"alpha.dump_book": 0.9, "d_book": 0.8}


def test_dump_away_from_known_location_sets_nothing():
    d = FactDeriver(errands_rules(), facts=frozenset({"has-robot book"}))
    events, _ = run(d, 0.0, 1.0, **{"alpha.dump_book": 0.9, "d_book": 0.8})
    assert events == [] and d.facts == {"has-robot book"}


def test_synchronous_evaluation_uses_tick_start_facts():
    # at-robot a is set on this very tick; the dump rule must not see it until the next tick.
    d = FactDeriver(errands_rules(), facts=frozenset({"has-robot book"}))
    dump = {"alpha.dump_book": 0.9, "d_book": 0.8, "δ_a": 1.0}
    events, t = run(d, 0.0, 0.32, **dump)
    assert [e.fact for e in events] == ["at-robot a"]
    events, t = run(d, t, 0.28, **dump)
    assert events == []
    events, t = run(d, t, 0.04, **dump)
    assert [e.fact for e in events] == ["at book a", "has-robot book"]
    assert str(events[0]).endswith("+at book a (set)")


def test_event_log_and_reset(deriver):
    run(deriver, 0.0, 0.4, **{"δ_b": 1.0})
    # Rule order: a is cleared by its own dwell on the tick b is set.
    assert [(e.fact, e.value) for e in deriver.events] == [("at-robot a", False), ("at-robot b", True)]
    deriver.reset(INIT)
    assert deriver.facts == INIT


def test_errands_rules_read_only_signals_the_dd_model_publishes():
    from pathlib import Path

    from xabsl_studio.engine.dynamics.model import load_model
    from xabsl_studio.engine.dynamics.system import DDSystem

    path = Path(__file__).resolve().parents[2] / "examples/errands/model/errands_dd.json"
    dd = DDSystem(load_model(path))
    sensors = dict.fromkeys(dd.model.sensors, 0.0)
    published = set(dd.signals(sensors))
    read = {t.signal for r in errands_rules() for t in (*r.set_when, *r.veto_when, *r.clear_when) if t.signal}
    assert read <= published
    # And a derivation tick over real DD signals works end to end.
    d = FactDeriver(errands_rules(), facts=frozenset(INIT))
    assert d.update(0.02, dd.signals(sensors)) == []
