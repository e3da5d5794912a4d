"""The root of the conformance check's errors: every error class it defines derives from
:class:`ConformanceError` and keeps its builtin base (``ConnectionError`` for a link the
vehicle closed), so code catching that still catches it."""


class ConformanceError(Exception):
    """An error the conformance check raises on purpose."""
