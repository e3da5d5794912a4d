"""The root of the Monte-Carlo engine's errors: every error class it defines derives from
:class:`MontecarloError`, so a caller catches them all with one clause; input checks that
raise a plain ``ValueError`` stay ``ValueError``."""


class MontecarloError(Exception):
    """An error the Monte-Carlo engine raises on purpose."""
