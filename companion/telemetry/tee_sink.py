"""An EventSink that hands every event to several sinks (the mission log, then MQTT)."""

from __future__ import annotations

from typing import Any

from companion.telemetry.mission_log import EventSink


class TeeSink:
    def __init__(self, *sinks: EventSink) -> None:
        self.sinks = sinks

    def emit(self, t: float, event: str, **fields: Any) -> None:
        for sink in self.sinks:
            sink.emit(t, event, **fields)
