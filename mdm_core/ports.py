"""The project's MAVLink port convention (docs/architecture.md, "Ports"): the one source of every
default port, read by the companion, the emulator and the fleet.

PX4-like UDP: vehicle i (0-based, system id i + 1) talks to its companion on VEHICLE_UDP_BASE + i
and to ground stations on GCS_UDP; ArduPilot-like TCP: vehicle i serves TCP_BASE + TCP_STRIDE i.
"""

VEHICLE_UDP_BASE = 14540
VEHICLE_OWN_UDP_BASE = 14580
"""Vehicle i's own UDP port (PX4's local port of its offboard link)."""
GCS_UDP = 14550
TCP_BASE = 5760
TCP_STRIDE = 10
