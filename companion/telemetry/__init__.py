"""Telemetry out of the companion: the durable mission log; MQTT in companion.telemetry.mqtt."""

from companion.telemetry.mission_log import EventSink, MissionLog, Recovered, read_log, read_records

__all__ = ["EventSink", "MissionLog", "Recovered", "read_log", "read_records"]
