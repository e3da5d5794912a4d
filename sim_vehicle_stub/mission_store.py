"""A vehicle's stored plans (mission, fence, rally points) and the upload in progress of each.

Storage only: which items a persona takes, which answers it gives and how a mission is flown
live in ``mission_rules.py`` (the persona's data), ``mission_protocol.py`` (the messages) and
``mission_flight.py`` (AUTO). An item keeps what the wire carried (latitude and longitude in
1e-7 degrees, as MISSION_ITEM_INT), whether it came as MISSION_ITEM_INT or the legacy float
MISSION_ITEM, so a download hands back what was uploaded.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from sim_vehicle_stub.mavlink import dialect as d

MISSION: int = d.MAV_MISSION_TYPE_MISSION
FENCE: int = d.MAV_MISSION_TYPE_FENCE
RALLY: int = d.MAV_MISSION_TYPE_RALLY
PLAN_TYPES = (MISSION, FENCE, RALLY)


@dataclass(frozen=True)
class MissionItem:
    """One stored item."""

    command: int
    frame: int
    params: tuple[float, float, float, float]
    x: int
    """Latitude * 1e7 (a local or mission frame: the raw value)."""
    y: int
    z: float
    autocontinue: int = 1


@dataclass
class Upload:
    """An upload (MISSION_COUNT or MISSION_WRITE_PARTIAL_LIST) waiting for its items."""

    first: int
    """Sequence number of the first item asked for (0, or a partial list's start)."""
    last: int
    """Sequence number of the last item (inclusive)."""
    items: list[MissionItem] = field(default_factory=list)
    peer: tuple[int, int] = (0, 0)
    """System and component of the uploading client."""

    @property
    def next_seq(self) -> int:
        return self.first + len(self.items)

    @property
    def done(self) -> bool:
        return self.next_seq > self.last


@dataclass
class PlanStore:
    """One plan type of one vehicle: its items and the upload in progress (one at a time)."""

    items: list[MissionItem] = field(default_factory=list)
    upload: Upload | None = None
    revision: int = 0
    """Bumped whenever the stored items change (AUTO restarts a changed mission)."""

    def replace(self, items: list[MissionItem]) -> None:
        self.items = items
        self.upload = None
        self.revision += 1

    def finish(self, upload: Upload) -> None:
        """Store a completed upload: a full list replaces the plan, a partial one the items
        from its start (ArduPilot's MISSION_WRITE_PARTIAL_LIST)."""
        if upload.first == 0 and upload.last >= len(self.items) - 1:
            self.replace(upload.items)
            return
        merged = list(self.items)
        merged[upload.first : upload.last + 1] = upload.items
        self.replace(merged)


@dataclass
class VehiclePlans:
    """The three plan types of one vehicle."""

    stores: dict[int, PlanStore] = field(
        default_factory=lambda: {kind: PlanStore() for kind in PLAN_TYPES}
    )
    legacy_requests: bool = True
    """PX4 asks for the next item the way the last item came (MISSION_REQUEST after a float
    MISSION_ITEM, MISSION_REQUEST_INT after MISSION_ITEM_INT), legacy first after boot."""

    def __getitem__(self, kind: int) -> PlanStore:
        return self.stores[kind]

    @property
    def mission(self) -> PlanStore:
        return self.stores[MISSION]

    @property
    def fence(self) -> PlanStore:
        return self.stores[FENCE]

    @property
    def rally(self) -> PlanStore:
        return self.stores[RALLY]
