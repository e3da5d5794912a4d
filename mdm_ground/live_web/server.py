"""The page's web server (aiohttp): the static page, the scene, a WebSocket of snapshots,
and operator commands."""

from __future__ import annotations

import asyncio
import json
import logging
import math
import uuid
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from importlib import resources
from typing import Any
from urllib.parse import urlsplit

import aiohttp
import aiomqtt
from aiohttp import web

from companion.telemetry.mqtt.commands import COMMANDS
from mdm_ground.live_web.access import Access, AccessError
from mdm_ground.live_web.fleet_state import FleetState, Sent
from mdm_ground.live_web.mqtt_feed import MqttFeed
from mdm_ground.live_web.replay import Replay

log = logging.getLogger(__name__)

PUSH_S = 0.25
"""Wall seconds between two snapshots on a live page's WebSocket."""
_STATIC = resources.files("mdm_ground.live_web") / "static"
_STATIC_FILES = {"index.html": "text/html", "app.js": "text/javascript", "style.css": "text/css"}


@dataclass
class LivePage:
    """What one server shows: a live team (``state`` fed by ``feed``) or a replay."""

    scene: dict[str, Any]
    access: Access
    state: FleetState | None = None
    feed: MqttFeed | None = None
    replay: Replay | None = None
    clock: Callable[[], float] | None = None
    """Wall clock for link ages (time.time)."""
    sockets: set[web.WebSocketResponse] = field(default_factory=set)
    """The pages connected now."""

    def describe(self) -> dict[str, Any]:
        return self.scene | {
            "read_only": self.access.read_only or self.feed is None,
            "token_required": self.access.token is not None,
            "replay": None if self.replay is None else {"start": 0.0, "end": self.replay.end},
            "commands": list(COMMANDS),
        }


def make_app(page: LivePage) -> web.Application:
    """The aiohttp application of ``page``."""
    app = web.Application(middlewares=[_errors])
    app.router.add_get("/", _file_handler("index.html"))
    for name in _STATIC_FILES:
        app.router.add_get(f"/static/{name}", _file_handler(name))

    async def describe(_: web.Request) -> web.Response:
        return _json(page.describe())

    app.router.add_get("/api/scene", describe)
    app.router.add_get("/ws", lambda r: _socket(page, r))
    app.router.add_post("/api/command", lambda r: _command(page, r))

    async def close_sockets(_: web.Application) -> None:
        # an open page would otherwise hold the shutdown for its whole timeout
        for ws in list(page.sockets):
            await ws.close(code=aiohttp.WSCloseCode.GOING_AWAY, message=b"server shutdown")

    app.on_shutdown.append(close_sockets)
    return app


def _json(data: dict[str, Any], status: int = 200) -> web.Response:
    return web.json_response(data, status=status, dumps=lambda d: json.dumps(d, default=str))


@web.middleware
async def _errors(
    request: web.Request, handler: Callable[[web.Request], Awaitable[web.StreamResponse]]
) -> web.StreamResponse:
    """Every refusal as JSON ``{"error": ...}`` with its status."""
    try:
        return await handler(request)
    except AccessError as exc:
        log.warning("%s %s refused (%d): %s", request.method, request.path, exc.status, exc)
        return _json({"error": str(exc)}, exc.status)
    except web.HTTPException as exc:
        if exc.status < 400:
            raise
        return _json({"error": f"{exc.reason}: {request.method} {request.path}"}, exc.status)


def _file_handler(name: str) -> Callable[[web.Request], Awaitable[web.Response]]:
    async def serve(_: web.Request) -> web.Response:
        body = (_STATIC / name).read_bytes()
        return web.Response(
            body=body, content_type=_STATIC_FILES[name], headers={"Cache-Control": "no-store"}
        )

    return serve


async def _command(page: LivePage, request: web.Request) -> web.Response:
    """``POST /api/command`` ``{"vehicle": I or "all", "command": ...}``, the token (if any)
    in ``Authorization: Bearer``; 202 with the command's id once the broker has it."""
    origin = request.headers.get("Origin")
    if origin is not None and urlsplit(origin).netloc != request.host:
        raise AccessError(403, f"cross-site request from {origin} refused")
    if page.feed is None:
        raise AccessError(403, "no commands here: this page replays a finished run")
    auth = request.headers.get("Authorization", "")
    page.access.check_command(auth.removeprefix("Bearer ").strip() or None)
    try:
        body = await request.json()
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise AccessError(400, f"request body: not JSON ({exc})") from None
    if not isinstance(body, dict) or set(body) - {"vehicle", "command"}:
        raise AccessError(
            400,
            'request body: expected {"vehicle": I or "all", "command": '
            f"one of {', '.join(COMMANDS)}}}",
        )
    command, vehicle = body.get("command"), body.get("vehicle")
    if command not in COMMANDS:
        raise AccessError(400, f"command {command!r}: expected one of {', '.join(COMMANDS)}")
    if vehicle != "all" and (
        isinstance(vehicle, bool) or not isinstance(vehicle, int) or not 0 <= vehicle < 10000
    ):
        raise AccessError(400, f'vehicle {vehicle!r}: expected a vehicle index or "all"')
    ref = uuid.uuid4().hex[:12]
    try:
        await page.feed.send(None if vehicle == "all" else vehicle, command, ref)
    except aiomqtt.MqttError as exc:
        raise AccessError(503, f"the broker did not take the command: {exc}") from None
    log.info("command %s to %s sent (id %s)", command, vehicle, ref)
    return _json({"id": ref, "command": command, "vehicle": vehicle}, 202)


async def _socket(page: LivePage, request: web.Request) -> web.WebSocketResponse:
    """Live: a snapshot every PUSH_S. Replay: a snapshot of the asked time per ``{"seek": t}``."""
    ws = web.WebSocketResponse(heartbeat=20.0)
    await ws.prepare(request)
    page.sockets.add(ws)
    try:
        if page.replay is not None:
            await _replay_socket(page.replay, ws)
        else:
            await _live_socket(page, ws)
    finally:
        page.sockets.discard(ws)
    return ws


async def _live_socket(page: LivePage, ws: web.WebSocketResponse) -> None:
    """A snapshot, then the next once the page has drawn it (its ``ack``) and PUSH_S has
    passed: a page that draws slowly (a loaded host) gets fewer, current snapshots instead of
    a queue of old ones."""
    state, clock = page.state, page.clock
    assert state is not None, "a live page has a state"
    assert clock is not None, "a live page has a clock"
    sent = Sent()
    loop = asyncio.get_running_loop()
    try:
        while not ws.closed:
            started = loop.time()
            await ws.send_str(json.dumps(state.snapshot(clock(), sent)))
            msg = await ws.receive()
            if msg.type != aiohttp.WSMsgType.TEXT:
                break  # closed, closing or an error
            await asyncio.sleep(max(0.0, started + PUSH_S - loop.time()))
    except (ConnectionResetError, aiohttp.ClientConnectionResetError):
        pass


async def _replay_socket(replay: Replay, ws: web.WebSocketResponse) -> None:
    async for msg in ws:
        if msg.type != aiohttp.WSMsgType.TEXT:
            continue
        try:
            t = float(json.loads(msg.data)["seek"])
            if not math.isfinite(t):
                raise ValueError(f"seek {t}: not a finite time")
        except (ValueError, KeyError, TypeError) as exc:
            await ws.send_str(
                json.dumps({"type": "error", "error": f'expected {{"seek": t}}: {exc}'})
            )
            continue
        snap = replay.state_at(min(max(t, 0.0), replay.end)).snapshot(0.0)
        await ws.send_str(json.dumps(snap | {"reset": True, "at": t}))
