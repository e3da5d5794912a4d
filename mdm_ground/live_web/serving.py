"""Run a page's server (and its MQTT feed) until SIGINT or SIGTERM."""

from __future__ import annotations

import asyncio
import contextlib
import signal
import sys

from aiohttp import web

from mdm_ground.live_web.server import LivePage, make_app


async def serve(page: LivePage, host: str, port: int, *, token_printed: bool) -> None:
    """Serve ``page`` on ``host:port`` (0: a free port); print its address (with the token
    when it was generated here) on stdout; return after SIGINT or SIGTERM."""
    runner = web.AppRunner(make_app(page), access_log=None, shutdown_timeout=5.0)
    await runner.setup()
    site = web.TCPSite(runner, host, port)
    try:
        await site.start()
    except OSError as exc:
        await runner.cleanup()
        raise ValueError(f"--web {host}:{port}: cannot listen: {exc.strerror}") from None
    bound = runner.addresses[0][1] if runner.addresses else port
    shown = f"[{host}]" if ":" in host else host
    url = f"http://{shown}:{bound}/"
    if token_printed and page.access.token is not None:
        url += f"#token={page.access.token}"
    print(f"web: {url}", flush=True)
    if token_printed:
        print("web: commands need this token (bound beyond loopback)", file=sys.stderr, flush=True)
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, stop.set)
    feed = None if page.feed is None else asyncio.create_task(page.feed.channel.run())
    try:
        await stop.wait()
    finally:
        if feed is not None:
            feed.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await feed
        await runner.cleanup()
