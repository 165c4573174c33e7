"""Whole-program checks the original compiler never had.

* ``option-graph-cycle`` (error): an option that can reach itself through subsequent-option calls
  would be "contained in the activation tree more than once" at run time (§2.10);
* ``unreachable-option``: no agent's root reaches it (only when the program has agents);
* ``unreachable-state``: no transition chain from the initial state leads to it;
* ``unused-symbol`` / ``unused-behavior``: declared, never used (only when the program has agents).
"""

from __future__ import annotations

from xabsl_studio.engine import ir
from xabsl_studio.engine.lang.diagnostics import Diagnostics


def option_calls(option: ir.Option) -> list[ir.OptionCall]:
    """Every subsequent-option call of an option (states with common action inlined)."""
    return [a for s in option.states for a in s.actions if isinstance(a, ir.OptionCall)]


def check_cycles(options: dict[str, ir.Option], diagnostics: Diagnostics) -> None:
    """Report options that can reach themselves through subsequent-option calls."""
    white, grey, black = 0, 1, 2
    color = dict.fromkeys(options, white)
    reported: set[frozenset[str]] = set()

    def visit(name: str, path: list[str]) -> None:
        color[name] = grey
        path.append(name)
        seen_calls: set[str] = set()
        for call in option_calls(options[name]):
            callee = call.option
            if callee not in options or callee in seen_calls:
                continue
            seen_calls.add(callee)
            if color[callee] == grey:
                cycle = path[path.index(callee) :]
                key = frozenset(cycle)
                if key not in reported:
                    reported.add(key)
                    loop = " -> ".join([*cycle, callee])
                    diagnostics.add(
                        "option-graph-cycle",
                        f"option graph cycle: {loop} (an option may not be active twice in one tick)",
                        call.span,
                    )
            elif color[callee] == white:
                visit(callee, path)
        path.pop()
        color[name] = black

    for name in options:
        if color[name] == white:
            visit(name, [])


def check_reachability(program: ir.Program, diagnostics: Diagnostics) -> None:
    """Warn about options no agent reaches and states no transition enters."""
    if program.agents:
        reached: set[str] = set()
        stack = [a.root for a in program.agents if a.root in program.options]
        while stack:
            name = stack.pop()
            if name in reached:
                continue
            reached.add(name)
            stack.extend(c.option for c in option_calls(program.options[name]) if c.option in program.options)
        for option in program.options.values():
            if option.name not in reached:
                diagnostics.add(
                    "unreachable-option", f"option '{option.name}' is not reachable from any agent", option.span
                )
    for option in program.options.values():
        if not option.states:
            continue
        seen = {option.initial_state}
        stack = [option.initial_state]
        while stack:
            state = option.state(stack.pop())
            for leaf in ir.leaves(state.decision):
                if (
                    leaf.target is not None
                    and leaf.target not in seen
                    and leaf.target in {s.name for s in option.states}
                ):
                    seen.add(leaf.target)
                    stack.append(leaf.target)
        for state in option.states:
            if state.name not in seen:
                diagnostics.add(
                    "unreachable-state",
                    f"state '{state.name}' of option '{option.name}' is not reachable from the initial state",
                    state.span,
                )


def check_unused(program: ir.Program, usage: set[tuple[str, str]], diagnostics: Diagnostics) -> None:
    """Warn about declared symbols, enumerations and basic behaviors that nothing uses."""
    if not program.agents:
        return
    used_enums = {e for klass, e in usage if klass == "enum"}
    used_enums.update(s.enum for s in program.inputs.values() if s.enum)
    used_enums.update(s.enum for s in program.outputs.values() if s.enum)
    for symbol in program.inputs.values():  # only input symbols have parameters
        used_enums.update(p.enum for p in symbol.params if p.enum)
    for option in program.options.values():
        used_enums.update(p.enum for p in option.params if p.enum)
    for behavior in program.behaviors.values():
        used_enums.update(p.enum for p in behavior.params if p.enum)

    for symbol in program.inputs.values():
        if ("input", symbol.name) not in usage:
            diagnostics.add("unused-symbol", f"input symbol '{symbol.name}' is never used", symbol.span)
    for output in program.outputs.values():
        written = ("output-write", output.name) in usage
        read = ("output-read", output.name) in usage
        if not written and not read:
            what = "internal symbol" if output.internal else "output symbol"
            diagnostics.add("unused-symbol", f"{what} '{output.name}' is never set or read", output.span)
    for constant in program.constants.values():
        if ("constant", constant.name) not in usage:
            diagnostics.add("unused-symbol", f"constant '{constant.name}' is never used", constant.span)
    for enum in program.enums.values():
        if enum.name not in used_enums:
            diagnostics.add("unused-symbol", f"enumeration '{enum.name}' is never used", enum.span)
    for behavior in program.behaviors.values():
        if ("behavior", behavior.name) not in usage:
            diagnostics.add("unused-behavior", f"basic behavior '{behavior.name}' is never called", behavior.span)
