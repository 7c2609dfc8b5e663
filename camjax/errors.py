"""Errors camjax raises (floor 1: imports nothing from camjax)."""


class SolverError(RuntimeError):
    """A solution path failed (step limit, non-finite values, a broken invariant): no result."""
