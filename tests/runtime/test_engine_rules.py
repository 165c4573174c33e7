"""One test per rule of §2, the subtle ones first. Programs are IC snippets (§3.2)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.runtime.helpers import Host, ic
from xabsl_studio.engine.codegen.support import modulo, modulo_by, to_int32
from xabsl_studio.engine.runtime import Bindings, Engine

# -- §2.2 decision before action, also on the activation tick -----------------------------------

LEAVE_INITIAL = """
0 0 1 main 0
2 a n b n a
0 1 d ran_a v 1        // a: sets ran_a
  i > i x 0 v 0 t b t a
0 1 d ran_b v 1        // b
  t b
1 solo main
"""


def test_option_leaves_its_initial_state_on_the_activation_tick() -> None:
    host = Host(ic(LEAVE_INITIAL))
    engine = host.tick(0, x=1.0)
    assert host.state("main") == "b"
    assert engine.output("ran_a") == 0.0, "the initial state's actions never ran"
    assert engine.output("ran_b") == 1.0
    assert host.node("main").state_time == 0


ONE_TRANSITION = """
0 0 1 main 0
3 a n b n c n a
0 0 t b
0 0 t c
0 0 t c
1 solo main
"""


def test_at_most_one_transition_per_option_per_tick() -> None:
    host = Host(ic(ONE_TRANSITION))
    host.tick(0)
    assert host.state("main") == "b"
    host.tick(10)
    assert host.state("main") == "c"


# -- §2.2 re-initialisation only after a tick without a call -----------------------------------

REINIT = """
0 0 2 child 0 parent 0
2 c1 n c2 n c1                        // child
0 0 i i go 0 t c2 t c1
0 0 t c2
3 p1 n p2 n idle n p1                 // parent: mode 0 -> p1, 1 -> p2, 2 -> idle
0 1 o child 0  i = i mode 0 v 1 t p2 i = i mode 0 v 2 t idle t p1
0 1 o child 0  i = i mode 0 v 1 t p2 i = i mode 0 v 2 t idle t p1
0 0            i = i mode 0 v 1 t p2 i = i mode 0 v 2 t idle t p1
1 solo parent
"""


def test_reinitialisation_after_one_idle_tick() -> None:
    host = Host(ic(REINIT))
    host.tick(0, mode=0.0, go=True)
    assert host.state("child") == "c2"
    host.tick(10, mode=2.0, go=False)
    assert not host.ran("child")
    host.tick(20, mode=0.0)
    assert host.state("child") == "c1", "one tick without a call restarts the option"
    assert host.node("child").option_time == 0


def test_option_called_from_both_parent_states_keeps_its_state() -> None:
    host = Host(ic(REINIT))
    host.tick(0, mode=0.0, go=True)
    host.tick(10, mode=1.0, go=False)
    assert host.state("parent") == "p2"
    assert host.state("child") == "c2"
    assert host.node("child").option_time == 10


# -- §2.7 action_done reads the previous tick ---------------------------------------------------

ACTION_DONE = """
0 0 2 child 0 parent 0
2 s n done n s
0 0 t done
1 0 t done                            // done: target state
2 wait n finished n wait
0 1 o child 0  i t t finished t wait
0 1 a beep 0   i t t finished t finished
1 solo parent
"""


def test_action_done_lags_one_tick() -> None:
    host = Host(ic(ACTION_DONE))
    host.tick(0)
    assert host.state("child") == "done", "the child reached its target state in this tick"
    assert host.state("parent") == "wait", "but the parent decided before the child ran"
    host.tick(10)
    assert host.state("parent") == "finished"


def test_action_done_is_false_without_subsequent_options() -> None:
    host = Host(ic(ACTION_DONE))
    host.tick(0)
    host.tick(10)
    host.tick(20)
    assert host.state("parent") == "finished"  # only a basic behavior: action_done is false, stays


# -- §2.2 outputs are written through ------------------------------------------------------------

WRITE_THROUGH = """
0 0 2 child 1 d child.v main 0
1 k n k
0 2 d q p child.v d w v 7 t k
1 s n s
0 5 d o v 5
    d p + o o v 1
    o child 1 d child.v o o
    d o v 9
    d r o w
  t s
1 solo main
"""


def test_write_through_is_read_later_in_the_same_tick() -> None:
    engine = Host(ic(WRITE_THROUGH)).tick(0)
    assert engine.output("p") == 6.0, "read back in the same option"
    assert engine.output("q") == 5.0, "passed to a child as a parameter"
    assert engine.output("r") == 7.0, "a child's write read by the parent after the call"
    assert engine.output("o") == 9.0, "later writes win"


NEVER_RESET = """
0 1 d memory 1 main 0
2 a n b n a
0 2 d o v 1 d memory + o memory v 1  i > i x 0 v 0 t b t a
0 0 t b
1 solo main
"""


def test_outputs_and_internal_symbols_are_never_reset() -> None:
    host = Host(ic(NEVER_RESET))
    host.tick(0, x=0.0)
    host.tick(10, x=1.0)  # main enters b, which assigns nothing
    engine = host.tick(20)
    assert host.state("main") == "b"
    assert engine.output("o") == 1.0
    assert engine.output("memory") == 1.0


# -- §2.5 parameters -------------------------------------------------------------------------------

CLOBBER = """
0 0 1 main 0
1 s n s
0 2 d r i f 2 d f.x v 3 d f.y i f 2 d f.x v 1 d f.y v 1
    d r2 i g 2 b g.first > i g 2 b g.first v true d g.x v 1 v 0 d g.x v 5
  t s
1 solo main
"""


def test_nested_call_of_the_same_input_symbol_clobbers_its_parameters() -> None:
    engine = Host(ic(CLOBBER)).tick(0)
    # f = x + 2y. Inner f(1, 1) = 3 overwrote x: the outer call sees x = 1, y = 3.
    assert engine.output("r") == 7.0


def test_decimal_parameters_are_set_before_boolean_ones() -> None:
    engine = Host(ic(CLOBBER)).tick(0)
    # g = first + 2x. The engine sets x = 5 first, then evaluates first, whose inner call sets
    # x = 1: the outer call sees first = true, x = 1.
    assert engine.output("r2") == 3.0


ENUM_DEFAULT = """
0 0 2 child 1 e mode child.m main 0
1 k n k
0 1 e out p child.m  i c p child.m v mode.a t k i c p child.m v mode.b t k t k
1 s n s
0 1 o child 0  t s
1 solo main
"""


def test_unassigned_enum_parameter_is_raw_zero() -> None:
    program = ic(ENUM_DEFAULT)
    bindings = Bindings()
    bindings.enum("mode", {"mode.a": 5, "mode.b": 7})
    bindings.output("out", program.outputs["out"].kind, enum="mode")
    engine = Engine(bindings, program)
    assert engine.output("out") == 5, "an output starts at the first element"
    engine.execute(0)
    print(engine.activation_dict())
    assert engine.output("out") == 0, "the default is the raw value 0, not the first element"


DEFAULTS_EACH_CALL = """
0 0 2 child 2 d child.v b child.on main 0
1 k n k
0 0 t k
2 p1 n p2 n p1
0 1 o child 2 d child.v i x 0 b child.on v true  i > i x 0 v 5 t p2 t p1
0 1 o child 0                                    t p2
1 solo main
"""


def test_parameters_are_re_evaluated_and_defaults_re_applied_on_every_call() -> None:
    host = Host(ic(DEFAULTS_EACH_CALL))
    host.tick(0, x=3.0)
    assert host.node("child").params == {"child.v": 3.0, "child.on": True}
    host.tick(10, x=4.0)
    assert host.node("child").params == {"child.v": 4.0, "child.on": True}
    host.tick(20, x=9.0)  # main leaves p1 in its decision: p2 calls child() without arguments
    assert host.node("child").params == {"child.v": 0.0, "child.on": False}


# -- §2.6 time --------------------------------------------------------------------------------------

TIMES = """
0 0 1 main 0
2 a n b n a
0 2 d st_a s d ot_a t  i g s v 100 t b t a
0 2 d st_b s d ot_b t  t b
1 solo main
"""


def test_state_time_starts_at_zero_on_entry_and_option_time_runs_on() -> None:
    host = Host(ic(TIMES))
    engine = host.tick(1000)
    assert (engine.output("st_a"), engine.output("ot_a")) == (0.0, 0.0)
    engine = host.tick(1050)
    assert engine.output("st_a") == 50.0
    engine = host.tick(1100)  # decision sees state_time 100: enters b, whose actions see 0
    assert host.state("main") == "b"
    assert (engine.output("st_b"), engine.output("ot_b")) == (0.0, 100.0)
    engine = host.tick(1130)
    assert (engine.output("st_b"), engine.output("ot_b")) == (30.0, 130.0)


def test_time_going_backwards_is_unsigned_32_bit() -> None:
    host = Host(ic(TIMES))
    host.tick(1000)
    host.tick(1100)
    engine = host.tick(5)
    assert engine.output("st_b") == float(2**32 - 1095)
    assert engine.output("ot_b") == float(2**32 - 995)
    assert host.node("main").option_time == 2**32 - 995


GOTO_SELF = """
0 0 1 main 0
1 a n a
0 0 t a
1 solo main
"""


def test_goto_self_is_stay_and_does_not_reset_state_time() -> None:
    host = Host(ic(GOTO_SELF))
    host.tick(0)
    host.tick(250)
    assert host.node("main").state_time == 250


# -- §2.8 expressions --------------------------------------------------------------------------------

ARITHMETIC = """
0 0 1 main 0
1 s n s
0 6 d div0 d v 1 v 0
    d divneg0 d v 2 i x 0
    d mod % v -7 v 3
    d modfrac % v 7.9 v -2.5
    d neg - v 0 i x 0
    d exact q = + v 0.1 v 0.2 v 0.3 v 1 v 0
  t s
1 solo main
"""


def test_division_by_zero_divides_by_1e_minus_7_and_modulo_truncates() -> None:
    engine = Host(ic(ARITHMETIC)).tick(0, x=-0.0)
    assert engine.output("div0") == 1 / 1e-7
    assert engine.output("divneg0") == 2 / 1e-7, "-0.0 is an exact zero divisor too"
    assert engine.output("mod") == -1.0, "C++ % keeps the dividend's sign"
    assert engine.output("modfrac") == 1.0, "(int)7.9 % (int)-2.5 == 7 % -2"
    assert str(engine.output("neg")) == "0.0", "unary minus is 0 - x: -(-0.0) is +0.0"
    assert engine.output("exact") == 0.0, "comparisons are exact doubles: 0.1 + 0.2 != 0.3"


def test_modulo_by_zero_is_a_fault() -> None:
    program = ic("0 0 1 main 0 1 s n s 0 1 d r % v 1 i x 0 t s 1 solo main")
    engine = Host(program).tick(0)
    assert engine.fault is not None and "ZeroDivisionError" in engine.fault.message


SHORT_CIRCUIT = """
0 0 1 main 0
1 s n s
0 3 b r1 & 2 v false i probe 1 d probe.a v 1
    b r2 | 2 v true i probe 1 d probe.a v 2
    b r3 & 3 i probe 1 d probe.a v 3 i probe 1 d probe.a v 4 v false
  t s
1 solo main
"""


def test_and_or_are_n_ary_and_short_circuit_left_to_right() -> None:
    calls: list[float] = []

    def probe(a: float) -> bool:
        calls.append(a)
        return True

    engine = Host(ic(SHORT_CIRCUIT), probe=probe).tick(0)
    assert calls == [3.0, 4.0]
    assert (engine.output("r1"), engine.output("r2"), engine.output("r3")) == (False, True, False)


# -- §2.9 agents, reset ----------------------------------------------------------------------------

AGENTS = """
0 0 2 child 0 main 0
2 c1 n c2 n c1
0 0 t c2
0 0 t c2
1 m n m
0 1 o child 0 t m
2 first main second child
"""


def test_select_agent_resets_nothing() -> None:
    host = Host(ic(AGENTS))
    host.tick(0)
    host.tick(10)
    host.engine.root_actions.select_agent("second")
    host.tick(20)
    assert host.engine.activation()[0].option == "child"
    assert host.state("child") == "c2", "the child was active in the previous tick: it continues"
    assert host.node("child").option_time == 20
    host.engine.root_actions.select_agent("first")
    host.tick(30)
    assert host.node("main").option_time == 0, "main was not executed in the previous tick"


def test_reset_reinitialises_every_option() -> None:
    host = Host(ic(AGENTS))
    host.tick(0)
    host.tick(10)
    host.engine.reset()
    host.tick(20)
    assert host.node("child").option_time == 0
    assert host.state("child") == "c2"  # left c1 on its (re)activation tick


@pytest.mark.parametrize("now", [0, 2**32 + 7])
def test_one_clock_per_tick_taken_modulo_2_32(now: int) -> None:
    host = Host(ic(TIMES))
    host.tick(now)
    assert host.engine.now == now % 2**32


@given(
    st.floats(allow_nan=True, allow_infinity=True) | st.integers(-(2**33), 2**33).map(float),
    st.floats(allow_nan=False, allow_infinity=False, min_value=-(2.0**32), max_value=2.0**32).filter(to_int32),
)
def test_modulo_by_a_constant_divisor_is_modulo(a: float, b: float) -> None:
    # the code generator's fast path for `x % 3` (the divisor truncated once) against the general rule
    assert modulo_by(a, abs(to_int32(b))) == modulo(a, b)
