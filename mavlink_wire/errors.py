"""The root of the wire package's errors: every error class it defines derives from
:class:`SigningError` and keeps its builtin base (``ValueError`` for a key that cannot be
used), so code catching that still catches it."""


class SigningError(Exception):
    """An error the wire package raises on purpose."""
