"""The root of the profiles package's errors: every error class it defines derives from
:class:`ProfilesError` and keeps its builtin base (``ValueError`` for a profile that cannot be
used), so code catching that still catches it."""


class ProfilesError(Exception):
    """An error the profiles package raises on purpose."""
