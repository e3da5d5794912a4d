"""The root of the companion's errors: every error it raises on purpose derives from
:class:`CompanionError`, so a caller (a script around ``fly``, a ground tool) catches them all
with one clause. Each subclass also keeps the builtin base it had (``ValueError`` for bad input,
``RuntimeError`` for a link or vehicle that failed), so code catching those still catches them."""


class CompanionError(Exception):
    """An error the companion raises on purpose; the message says what and where."""


class InputError(CompanionError, ValueError):
    """Input the companion cannot use (a connection address, a backend, a flight's settings);
    the message names what and where."""
