"""The root of the ground tools' errors. :class:`GroundError` is a
:class:`~companion.errors.CompanionError`, so the `companion` command and scripts around the fleet
catch the vehicle's and the ground's errors with one clause; each subclass also keeps its builtin
base (``ValueError`` for bad input)."""

from companion.errors import CompanionError


class GroundError(CompanionError):
    """An error a ground tool raises on purpose; the message says what and where."""
