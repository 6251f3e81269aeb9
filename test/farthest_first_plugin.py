"""A strategy plug-in module for the tests: importing it registers ``farthest_first``
(the farthest reachable frontier first), as a user's module would."""

from explore_seg.core.selection import Strategy, register

NAME = "farthest_first_plugin"


def farthest_cost(inp, params):
    """The farthest reachable frontier first (the opposite of nearest)."""
    return -inp.dist_m[inp.finite]


register(Strategy(NAME, farthest_cost, "the farthest frontier first"), replace=True)
