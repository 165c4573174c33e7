"""Example worlds that host XABSL behaviors: robot soccer and the errands robot.

Each example is a package with its world (physics, rules, perception), the symbol and basic
behavior bindings, and its ``behavior/*.xabsl`` sources. Examples depend on ``engine``; the
engine never imports them.
"""
