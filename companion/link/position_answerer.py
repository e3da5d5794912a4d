"""The search's fast path through a link: a position that only needs steering is answered at
once, without the events' path (mission/search_answer.py implements it)."""

from __future__ import annotations

from typing import Protocol

from companion.link.messages import LinkEvent, LocalPosition


class PositionAnswerer(Protocol):
    """Takes a position that only needs steering, without the events' path."""

    def ready(self, vehicle_time: float, north: float, east: float) -> bool:
        """Whether this position (vehicle s, profile frame) only needs steering."""

    def answer(
        self,
        pos: LocalPosition,
        signal: float | None,
        before: list[LinkEvent],
        after: list[LinkEvent],
    ) -> None:
        """Steer from ``pos``; ``signal``: the sensor's SENS_SIG reading that came with it;
        ``before`` / ``after``: the other events of its datagram, in order."""
