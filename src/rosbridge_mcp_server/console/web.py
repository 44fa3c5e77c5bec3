"""The console's web side: a static page, one event stream, and the four things a person may do.

Routes (everything under ``/api`` needs the session secret in the ``X-Console-Secret`` header, but E-STOP,
which any page of the console's own origin may press):

* ``GET /`` (and its script and style): the page; it holds no robot data, only code;
* ``GET /api/events``: server-sent events, ``state`` (the hub's snapshot), ``frame`` (the camera), ``pose``
  and ``map`` (the map panel's pose and picture);
* ``GET /api/image-topics``: the image topics, for the camera picker, and the default (the colour camera);
* ``GET /api/confirmations/{id}``: one waiting confirmation (for a page opened by a link);
* ``POST /api/confirmations/{id}/approve`` and ``.../deny``, ``POST /api/estop``, ``POST /api/release``,
  ``POST /api/camera`` (``{"topic": "/camera/image_raw"}``, ``""`` for none), ``POST /api/map``
  (``{"topic": "/map", "base_frame": "base_link"}``).

There is no route that publishes, calls or sends anything of its own: the console approves, denies, stops
and releases, and nothing else. A header (not a cookie) carries the secret, so another page in the same
browser cannot make a request that counts, and a request whose ``Host`` is not the console's own address is
refused (a DNS-rebinding page would otherwise reach a loopback console).

A confirmation sent to the person by link (URL-mode elicitation) carries a token of its own in the URL's
fragment; the page sends it in ``X-Confirmation-Token``, which reads, approves or denies that one
confirmation while it waits, and nothing else (no event stream, no E-STOP, no other confirmation).

A stop never fails silently: a tab of the console opened without the secret (a bookmark, a second tab) still
shows a red E-STOP, so ``POST /api/estop`` is also taken without the secret when the browser says the request
comes from a page of the console's own origin (its ``Origin`` header is the console's own address). A page of
another site cannot send that header, and stopping only takes motion away; Release, Approve and everything
that reads the robot still need the secret.
"""

from __future__ import annotations

import hmac
import json
import logging
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any
from urllib.parse import urlsplit

from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import JSONResponse, Response, StreamingResponse
from starlette.routing import Route

from rosbridge_mcp_server.console.hub import ConsoleHub
from rosbridge_mcp_server.console.pages import static_text
from rosbridge_mcp_server.errors import RosbridgeError

__all__ = ["SECRET_HEADER", "TOKEN_HEADER", "console_app"]

_log = logging.getLogger("rosbridge_mcp_server.console")

SECRET_HEADER = "X-Console-Secret"
TOKEN_HEADER = "X-Confirmation-Token"
#: A comment line on an idle event stream, so proxies and the browser keep it open.
KEEP_ALIVE_SECONDS = 15.0
_SECURITY_HEADERS = {
    "Content-Security-Policy": (
        "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data:; connect-src 'self'; "
        "frame-ancestors 'none'; base-uri 'none'; form-action 'none'"
    ),
    "X-Frame-Options": "DENY",
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
    "Cache-Control": "no-store",
}
_STATIC = {
    "/": ("console.html", "text/html; charset=utf-8"),
    "/console.js": ("console.js", "text/javascript; charset=utf-8"),
    "/console.css": ("console.css", "text/css; charset=utf-8"),
}

Handler = Callable[[Request], Awaitable[Response]]


def console_app(hub: ConsoleHub, secret: str, allowed_hosts: set[str]) -> Starlette:
    """The console as an ASGI app, for ``hub``, guarded by ``secret``; ``allowed_hosts`` are Host values."""
    guard = _Guard(hub, secret, allowed_hosts)
    api = _Api(hub)
    guarded, secret_or_token = guard.guarded, guard.secret_or_token
    routes = [Route(path, guard.page, methods=["GET"]) for path in _STATIC]
    routes += [
        Route("/api/events", guarded(api.events), methods=["GET"]),
        Route("/api/image-topics", guarded(api.image_topics), methods=["GET"]),
        Route("/api/confirmations/{id}", secret_or_token(api.confirmation), methods=["GET"]),
        Route("/api/confirmations/{id}/approve", secret_or_token(api.approve), methods=["POST"]),
        Route("/api/confirmations/{id}/deny", secret_or_token(api.deny), methods=["POST"]),
        Route("/api/estop", guarded(api.estop, own_origin_may=True), methods=["POST"]),
        Route("/api/release", guarded(api.release), methods=["POST"]),
        Route("/api/camera", guarded(api.camera), methods=["POST"]),
        Route("/api/map", guarded(api.map_panel), methods=["POST"]),
    ]
    return Starlette(routes=routes)


class _Guard:
    """Who reaches a route: the session secret on every ``/api`` route (an E-STOP from a page of the console's
    own origin without it), or a link's token for its one confirmation; the pages need the Host only."""

    def __init__(self, hub: ConsoleHub, secret: str, allowed_hosts: set[str]) -> None:
        self.hub = hub
        self.secret = secret
        self.allowed_hosts = allowed_hosts

    def guarded(self, handler: Handler, *, own_origin_may: bool = False) -> Handler:
        async def check(request: Request) -> Response:
            refusal = _refusal(request, self.secret, self.allowed_hosts, need_secret=True)
            if refusal is not None and own_origin_may and _from_own_origin(request, self.allowed_hosts):
                _log.warning(
                    "console: %s %s without the session secret, from a page of the console's own origin",
                    request.method,
                    request.url.path,
                )
                refusal = None
            return refusal if refusal is not None else await handler(request)

        return check

    def secret_or_token(self, handler: Handler) -> Handler:
        # The session secret, or the token of the one confirmation the path names (a link's).
        async def check(request: Request) -> Response:
            token = request.headers.get(TOKEN_HEADER)
            if token is None or request.headers.get(SECRET_HEADER) is not None:
                return await self.guarded(handler)(request)
            refusal = _refusal(request, self.secret, self.allowed_hosts, need_secret=False)
            if refusal is not None:
                return refusal
            if self.hub.operator.by_token(request.path_params["id"], token) is None:
                _log.warning(
                    "console: refused %s %s with a wrong or spent token", request.method, request.url.path
                )
                return _json(
                    {"error": "this link's confirmation is no longer waiting, or the link is wrong"}, 403
                )
            return await handler(request)

        return check

    async def page(self, request: Request) -> Response:
        refusal = _refusal(request, self.secret, self.allowed_hosts, need_secret=False)
        if refusal is not None:
            return refusal
        name, media_type = _STATIC[request.url.path]
        return Response(static_text(name), media_type=media_type, headers=_SECURITY_HEADERS)


class _Api:
    """The ``/api`` routes' handlers, on the hub (each reached through a :class:`_Guard`)."""

    def __init__(self, hub: ConsoleHub) -> None:
        self.hub = hub

    async def confirmation(self, request: Request) -> Response:
        pending = next((p for p in self.hub.operator.pending if p.id == request.path_params["id"]), None)
        if pending is None:
            return _json({"error": "this confirmation is no longer waiting"}, 404)
        act = pending.act
        return _json(
            {
                "id": pending.id,
                "tool": act.tool,
                "kind": act.kind,
                "name": act.name,
                "type": act.type,
                "question": pending.question,
                "asked_at": pending.asked_at,
            }
        )

    async def events(self, request: Request) -> Response:
        return StreamingResponse(
            _event_stream(self.hub),
            media_type="text/event-stream",
            headers={**_SECURITY_HEADERS, "X-Accel-Buffering": "no"},
        )

    async def image_topics(self, request: Request) -> Response:
        try:
            topics = await self.hub.image_topics()
        except RosbridgeError as exc:
            return _json({"error": str(exc)}, 503)
        return _json({"topics": topics, "default": await self.hub.default_camera(topics)})

    async def approve(self, request: Request) -> Response:
        return _answered(self.hub, request.path_params["id"], approve=True)

    async def deny(self, request: Request) -> Response:
        return _answered(self.hub, request.path_params["id"], approve=False)

    async def estop(self, request: Request) -> Response:
        reports = await self.hub.estop()
        return _json({"latched": True, "robots": reports})

    async def release(self, request: Request) -> Response:
        return _json({"released": self.hub.release(), "latched": False})

    async def camera(self, request: Request) -> Response:
        try:
            body = json.loads(await request.body() or b"{}")
        except ValueError:
            return _json({"error": 'the body must be JSON, e.g. {"topic": "/camera/image_raw"}'}, 400)
        topic = body.get("topic") if isinstance(body, dict) else None
        if topic is not None and (not isinstance(topic, str) or len(topic) > 256):
            return _json({"error": "topic must be a topic name (at most 256 characters) or empty"}, 400)
        try:
            self.hub.show_camera(topic or None)
        except RosbridgeError as exc:
            return _json({"error": str(exc)}, 400)
        return _json({"topic": self.hub.camera_topic})

    async def map_panel(self, request: Request) -> Response:
        try:
            body = json.loads(await request.body() or b"{}")
        except ValueError:
            body = None
        if not isinstance(body, dict):
            return _json(
                {"error": 'the body must be JSON, e.g. {"topic": "/map", "base_frame": "base_link"}'}, 400
            )
        topic, base = body.get("topic") or "", body.get("base_frame") or ""
        for key, value in (("topic", topic), ("base_frame", base)):
            if not isinstance(value, str) or len(value) > 256:
                return _json({"error": f"{key} must be a name (at most 256 characters) or empty"}, 400)
        try:
            self.hub.map.choose(topic, base)
        except RosbridgeError as exc:
            return _json({"error": str(exc)}, 400)
        return _json({"topic": self.hub.map.topic, "base_frame": self.hub.map.base_frame})


def _refusal(request: Request, secret: str, allowed_hosts: set[str], *, need_secret: bool) -> Response | None:
    host = request.headers.get("host", "")
    if host.lower() not in allowed_hosts:
        return _json({"error": "this console answers only at its own address"}, 421)
    if not need_secret:
        return None
    given = request.headers.get(SECRET_HEADER, "")
    if not hmac.compare_digest(given.encode(), secret.encode()):
        _log.warning("console: refused %s %s without the session secret", request.method, request.url.path)
        return _json({"error": f"this request needs the console's session secret in {SECRET_HEADER}"}, 403)
    return None


def _from_own_origin(request: Request, allowed_hosts: set[str]) -> bool:
    """Whether the browser says the request comes from a page of the console's own origin.

    Browsers send ``Origin`` with every POST and a page cannot set it; ``Host`` was already checked.
    """
    origin = urlsplit(request.headers.get("origin", ""))
    return origin.scheme in ("http", "https") and origin.netloc.lower() in allowed_hosts


def _answered(hub: ConsoleHub, pending_id: str, *, approve: bool) -> Response:
    if not hub.operator.answer(pending_id, approve):
        return _json({"error": f"confirmation {pending_id} is no longer waiting"}, 409)
    return _json({"id": pending_id, "answer": "approved" if approve else "denied"})


async def _event_stream(hub: ConsoleHub) -> AsyncIterator[str]:
    version = frame = pose = picture = -1
    hub.page_opened()
    try:
        while not hub.closed:
            seen = hub.marks()
            if hub.version != version:
                version = hub.version
                yield _event("state", hub.snapshot())
            if hub.frames != frame:
                frame = hub.frames
                shown = hub.frame_event()
                if shown is not None:
                    yield _event("frame", shown)
            if hub.map.poses != pose:
                pose = hub.map.poses
                yield _event("pose", {"pose": hub.map.pose_event()})
            if hub.map.images != picture:
                picture = hub.map.images
                yield _event("map", {"image": hub.map.image_event()})
            if not await hub.wait_changed(seen, KEEP_ALIVE_SECONDS):
                yield ": keep-alive\n\n"
    finally:
        hub.page_closed()


def _event(name: str, data: Any) -> str:
    return f"event: {name}\ndata: {json.dumps(data, ensure_ascii=False, separators=(',', ':'))}\n\n"


def _json(data: Any, status: int = 200) -> JSONResponse:
    return JSONResponse(data, status_code=status, headers={"Cache-Control": "no-store"})
