"""The live web page of a team: a map and table of every vehicle, served over HTTP and a
WebSocket by `companion watch`, `companion fleet --web` and `companion map --web`
(docs/live_web.md)."""
