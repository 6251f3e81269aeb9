"""Helpers shared by the benchmark tests (run_bench.py and paired.py)."""

from __future__ import annotations

from typing import Any, Callable


def failing_on_seed(run: Callable[..., Any], seed: int) -> Callable[..., Any]:
    """``run`` (a ``run_exploration``) that raises ``ValueError("boom")`` for ``seed``:
    one failing run among good ones (patched in before the pool forks)."""
    def flaky(world: Any, strategy: str, s: int, **kw: Any) -> Any:
        if s == seed:
            raise ValueError("boom")
        return run(world, strategy, s, **kw)
    return flaky
