"""The explorer's web page: a local trame app around :class:`~sciviz_gbuf.apps.explorer.Explorer`.

The picture travels as a JPEG data URL bound to an ``<img>`` (no remote VTK rendering): each
control change re-runs only the filters on the cached G-buffer and replaces the URL; camera
controls capture again. :func:`serve` (``sciviz-gbuf explore``) serves it on 127.0.0.1 only and
keeps the door shut to everything but the page it printed:

- a random per-launch secret (:func:`new_secret`) in the printed URL; the page sends it in
  wslink's hello (it replaces wslink's public default secret) and gets it back as a
  same-site cookie that the websocket handshake must present;
- the handshake's ``Host`` must be the served address and its ``Origin`` that same address
  (no other web page, no DNS rebinding);
- websocket frames and wslink messages are capped at :data:`MAX_MESSAGE_BYTES`, checked on the
  chunk header before wslink allocates the declared size, with at most
  :data:`MAX_PENDING_MESSAGES` half-received messages and :data:`MAX_CLIENTS` connections;
- the browser may set only the controls' state keys, each bounded like the Python API
  (:meth:`Params.checked <sciviz_gbuf.apps.explorer.Params.checked>`); a refused value is put
  back to the last good one;
- trame's options come from :func:`serve`'s arguments only (not ``TRAME_ARGS``, ``sys.argv``
  or ``--authKey``); SIGTERM/SIGINT stop the server, and while a render or capture holds the
  interpreter they end the process at once.
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import hmac
import ipaddress
import os
import secrets
import signal
import socket
import struct
import sys
import threading
import time
from collections.abc import Callable, Iterator

from .._atomic import one_line
from ..errors import InputError
from .explorer import RELIEF_VARIANTS, STYLES, VIEWS, encode_jpeg_data_url

__all__ = [
    "CAMERA",
    "MAP_SLIDERS",
    "MAX_CLIENTS",
    "MAX_MESSAGE_BYTES",
    "MAX_PENDING_MESSAGES",
    "PARAMS",
    "SLIDERS",
    "build_app",
    "check_port",
    "is_loopback",
    "new_secret",
    "serve",
]

#: Largest websocket frame and wslink message the server accepts from a browser (the page
#: sends a few hundred bytes per control change).
MAX_MESSAGE_BYTES = 1 << 20
#: Half-received (chunked) wslink messages per connection.
MAX_PENDING_MESSAGES = 8
#: Concurrent websocket connections.
MAX_CLIENTS = 8
#: wslink's chunk header: message id, offset, total size (little-endian uint32 each).
_CHUNK_HEADER = struct.Struct("<III")
#: The signals that stop the explorer.
_STOP_SIGNALS = (signal.SIGTERM, signal.SIGINT)
#: How long an error message in the page may be (a refused value is quoted in it).
_ERROR_CHARS = 300

#: Controls changing only image-space parameters: (state name, label, min, max, step).
SLIDERS = (
    ("crease_angle", "crease angle (°)", 1.0, 90.0, 1.0),
    ("depth_jump", "depth jump (pixel footprints)", 0.1, 10.0, 0.1),
    ("width", "line width (px)", 1.0, 6.0, 0.5),
    ("contour_width", "contour width (px)", 0.5, 5.0, 0.5),
    ("bands", "colour bands (0: none)", 0, 16, 1),
    ("light_azimuth", "light azimuth (°)", -180.0, 180.0, 1.0),
    ("light_elevation", "light elevation (°)", 0.0, 90.0, 1.0),
)
#: Controls of a DEM's plan-view map (``view == "map"``); the contour interval's range is the
#: DEM's (see :func:`build_app`).
MAP_SLIDERS = (
    ("map_azimuth", "light azimuth (° from north)", 0.0, 360.0, 1.0),
    ("map_altitude", "light altitude (°)", 1.0, 90.0, 1.0),
    ("z_factor", "z factor", 0.1, 10.0, 0.1),
    ("major_every", "major line every N minors", 1, 10, 1),
    ("map_width", "line width (px)", 0.5, 4.0, 0.5),
    ("map_bands", "bands (0 none, 1 ramp)", 0, 16, 1),
)
#: Camera controls (they capture again).
CAMERA = (
    ("camera_azimuth", "camera azimuth (°)", -180.0, 180.0, 1.0),
    ("camera_elevation", "camera elevation (°)", -89.0, 89.0, 1.0),
    ("camera_zoom", "zoom", 0.5, 4.0, 0.05),
)


#: Height of the page around the picture (toolbar and padding), so the picture fits the window.
_CHROME_PX = 96


def _wrap(expr: str) -> str:
    """A JavaScript expression of an azimuth in degrees wrapped into [-180, 180)."""
    return f"((({expr}) % 360 + 540) % 360 - 180)"


#: Parameters set by selects or ranged sliders rather than by :data:`SLIDERS`.
PARAMS = ("style", "contour_interval", "view", "relief", "map_interval")


def _dom_id(name: str) -> str:
    return "slider-" + name.replace("_", "-")


#: Every state key the browser may set: the controls' ``v_model`` names.
CONTROL_KEYS = frozenset(name for name, *_ in (*SLIDERS, *MAP_SLIDERS, *CAMERA)) | set(PARAMS)


def build_app(
    explorer,
    *,
    port: int = 8080,
    busy: Callable[[], contextlib.AbstractContextManager] = contextlib.nullcontext,
):
    """A trame server showing ``explorer``'s picture with a control per parameter.

    Parameters
    ----------
    explorer : Explorer
    port : int
        Names the trame server (one per port in a process).
    busy : callable, optional
        A context manager factory entered around each render and capture (:func:`serve` makes
        the stop signals end the process at once while one runs).

    Returns
    -------
    trame_server.Server, not started: :func:`serve` starts it with its door shut.
    """
    from trame.app import get_server
    from trame.ui.vuetify3 import SinglePageLayout
    from trame.widgets import html
    from trame.widgets import vuetify3 as v3

    server = get_server(
        f"sciviz-gbuf-explore-{port}", client_type="vue3", ws_max_msg_size=MAX_MESSAGE_BYTES
    )
    state = server.state
    p = explorer.params
    lo, hi = explorer.height_range
    span = max(hi - lo, 1e-9)
    # The map's interval slider: the default interval is on its grid of steps.
    q0 = (
        p.map_interval
        if p.map_interval > 0
        else float(f"{(explorer.map_range[1] - explorer.map_range[0]) / 40 or 1.0:.2g}")
    )
    has_map = explorer.dem is not None
    state.update(
        {
            "style": p.style,
            **{name: getattr(p, name) for name, *_ in SLIDERS},
            **{name: getattr(p, name) for name, *_ in MAP_SLIDERS},
            "view": p.view,
            "relief": p.relief,
            "map_interval": p.map_interval,
            "map_interval_max": q0 * 20,
            "map_interval_step": q0 / 4,
            "has_map": has_map,
            "contour_interval": p.contour_interval,
            "contour_max": float(f"{span / 2:.3g}"),
            "contour_step": float(f"{span / 200:.2g}"),
            "camera_azimuth": explorer.camera.azimuth,
            "camera_elevation": explorer.camera.elevation,
            "camera_zoom": explorer.camera.zoom,
            "image_url": "",
            "image_style": "max-width: 100%",
            "update_ms": 0.0,
            "filter_ms": 0.0,
            "error": "",
        }
    )
    param_keys = [name for name, *_ in (*SLIDERS, *MAP_SLIDERS)] + list(PARAMS)

    # Set while a refused value is being put back: the refresh that follows keeps the message.
    keep_error = [False]

    def refused(exc: Exception, good: dict) -> None:
        # The page shows why, and the controls go back to the last good values: a refused
        # value must not stay in the state (every later update would fail on it).
        state.error = one_line(str(exc), _ERROR_CHARS)
        back = {k: v for k, v in good.items() if state[k] != v}
        keep_error[0] = bool(back)
        state.update(back)

    def refresh() -> None:
        t0 = time.perf_counter()
        values = {name: state[name] for name in param_keys}
        try:
            with busy():
                rgb = explorer.render_image(values)
        except Exception as exc:  # shown in the page; the last good picture stays
            p = explorer.params
            refused(exc, {name: getattr(p, name) for name in param_keys})
            return
        if not keep_error[0]:
            state.error = ""
        keep_error[0] = False
        state.image_url = encode_jpeg_data_url(rgb)
        # A map has one pixel per DEM cell: small DEMs are shown enlarged.
        fit = f"max-width: 100%; max-height: calc(100vh - {_CHROME_PX}px); object-fit: contain"
        state.image_style = (
            f"width: {max(rgb.shape[1], 768)}px; {fit}" if values["view"] == "map" else fit
        )
        state.filter_ms = round(explorer.last_ms, 1)
        state.update_ms = round((time.perf_counter() - t0) * 1e3, 1)

    @state.change(*param_keys)
    def _on_params(**_) -> None:
        refresh()

    @state.change(*(name for name, *_ in CAMERA))
    def _on_camera(**_) -> None:
        try:
            with busy():
                explorer.set_camera(state.camera_azimuth, state.camera_elevation, state.camera_zoom)
        except Exception as exc:
            c = explorer.camera
            refused(
                exc,
                {"camera_azimuth": c.azimuth, "camera_elevation": c.elevation,
                 "camera_zoom": c.zoom},
            )  # fmt: skip
            return
        refresh()

    def slider(name: str, label: str, lo_: float, hi_, step) -> None:
        # The id sits on a wrapper: Vuetify hands a slider's own id to its label. The value is
        # always shown beside the label (a thumb label shows it only while dragging).
        with html.Div(id=_dom_id(name)):
            html.Div(
                f"{label}: {{{{ {name} }}}}",
                id=_dom_id(name) + "-value",
                classes="text-caption mt-1",
            )
            v3.VSlider(
                v_model=(name,),
                min=lo_,
                max=hi_,
                step=step,
                thumb_label=True,
                density="compact",
                hide_details=True,
                classes="mb-1",
                aria_label=label,
            )

    with SinglePageLayout(server) as layout:
        layout.title.set_text("sciviz-gbuf explorer")
        with layout.toolbar:
            v3.VSpacer()
            html.Span(
                "update {{ update_ms }} ms (filters {{ filter_ms }} ms)",
                id="update-text",
                classes="text-body-2",
            )
            html.Span("{{ update_ms }}", id="update-ms", style="display: none")
        with layout.content:
            with v3.VContainer(fluid=True, classes="d-flex flex-row pa-2"):
                with v3.VCol(cols=3, style="max-width: 320px; min-width: 260px"):
                    with html.Div(id="select-view", v_show="has_map"):
                        v3.VSelect(
                            v_model=("view",),
                            items=("views", list(VIEWS)),
                            label="view",
                            density="compact",
                            hide_details=True,
                        )
                    # The plan-view map of a DEM: no capture, its own controls.
                    with html.Div(id="map-controls", v_show="view === 'map'"):
                        with html.Div(id="select-relief"):
                            v3.VSelect(
                                v_model=("relief",),
                                items=("reliefs", list(RELIEF_VARIANTS)),
                                label="relief shade",
                                density="compact",
                                hide_details=True,
                            )
                        for spec in MAP_SLIDERS[:3]:
                            slider(*spec)
                        slider(
                            "map_interval",
                            "contour interval (0: none)",
                            0.0,
                            ("map_interval_max",),
                            ("map_interval_step",),
                        )
                        for spec in MAP_SLIDERS[3:]:
                            slider(*spec)
                    with html.Div(id="scene-controls", v_show="view !== 'map'"):
                        with html.Div(id="select-style"):
                            v3.VSelect(
                                v_model=("style",),
                                items=("styles", list(STYLES)),
                                label="style",
                                density="compact",
                                hide_details=True,
                            )
                        for spec in SLIDERS[:3]:
                            slider(*spec)
                        slider(
                            "contour_interval",
                            "contour interval (0: none)",
                            0.0,
                            ("contour_max",),
                            ("contour_step",),
                        )
                        for spec in SLIDERS[3:]:
                            slider(*spec)
                        v3.VDivider(classes="my-2")
                        for spec in CAMERA:
                            slider(*spec)
                    html.Div("{{ error }}", id="error", classes="text-error")
                # The picture: within the window (no scrolling to see it whole); focused, the
                # arrow keys orbit the camera (5° a press), + and - zoom.
                with v3.VCol(
                    id="view-box",
                    tabindex="0",
                    v_show="true",
                    v_on_keydown_left_prevent=(
                        f"view !== 'map' && (camera_azimuth = {_wrap('camera_azimuth - 5')})"
                    ),
                    v_on_keydown_right_prevent=(
                        f"view !== 'map' && (camera_azimuth = {_wrap('camera_azimuth + 5')})"
                    ),
                    v_on_keydown_up_prevent=(
                        "view !== 'map' && (camera_elevation = Math.min(89, camera_elevation + 5))"
                    ),
                    v_on_keydown_down_prevent=(
                        "view !== 'map' && (camera_elevation = Math.max(-89, camera_elevation - 5))"
                    ),
                    v_on_keydown=(
                        "view !== 'map' && ['+', '=', '-'].includes($event.key) && "
                        "(camera_zoom = $event.key === '-' ? "
                        "Math.max(0.5, +(camera_zoom / 1.1).toFixed(2)) : "
                        "Math.min(4, +(camera_zoom * 1.1).toFixed(2)))"
                    ),
                ):
                    html.Img(src=("image_url",), id="image", style=("image_style",))
    refresh()
    return server


# -- the door ----------------------------------------------------------------------------


def new_secret() -> str:
    """A random per-launch secret (256 bits, URL-safe)."""
    return secrets.token_urlsafe(32)


def is_loopback(host: str) -> bool:
    """Whether ``host`` names this machine only (``localhost``, 127.0.0.0/8, ``::1``)."""
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def _is_wildcard(host: str) -> bool:
    try:
        return ipaddress.ip_address(host.strip("[]")).is_unspecified
    except ValueError:
        return False


def _addresses(host: str, port: int) -> list[tuple]:
    """``getaddrinfo`` of a listening address, or an InputError naming ``--host``."""
    try:
        return socket.getaddrinfo(
            host.strip("[]"), port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE
        )
    except (socket.gaierror, UnicodeError) as exc:
        raise InputError(f"--host: cannot resolve {host!r} ({exc})") from None


def check_port(host: str, port: int) -> None:
    """An InputError naming ``--port`` unless a server can listen on ``host:port`` now.

    Binds (with ``SO_REUSEADDR``, as the server does) and closes again: a port another
    process listens on, or one below 1024 without the right, is refused before anything is
    loaded."""
    for family, kind, proto, _, addr in _addresses(host, port):
        with socket.socket(family, kind, proto) as s:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            try:
                s.bind(addr)
            except OSError as exc:
                raise InputError(_port_message(host, port, exc)) from None


def _port_message(host: str, port: int, exc: OSError) -> str:
    why = "is in use" if exc.errno == errno.EADDRINUSE else f"cannot be used ({exc.strerror})"
    return f"--port: port {port} on {host} {why}; expected a free port (try another --port)"


def _served_hosts(host: str, port: int) -> frozenset[str] | None:
    """The ``Host`` headers naming this server (``None`` for a wildcard address: any name
    that reaches it, the Origin must still be the same)."""
    if _is_wildcard(host):
        return None
    names = {host.strip("[]").lower()}
    names |= {addr[0] for *_, addr in _addresses(host, port)}
    if is_loopback(host):
        names |= {"localhost", "127.0.0.1", "::1"}
    out = set()
    for n in names:
        n = f"[{n}]" if ":" in n else n
        out.add(f"{n}:{port}")
        if port == 80:  # browsers leave the default port out of Host and Origin
            out.add(n)
    return frozenset(out)


def _same(a: str | None, b: str) -> bool:
    """Constant-time comparison of a presented secret (any text) with ``b``."""
    if not a:
        return False
    return hmac.compare_digest(a.encode("utf-8", "surrogateescape"), b.encode("utf-8"))


def _guard(secret: str, served: frozenset[str] | None, cookie: str, ws_path: str, clients):
    """The aiohttp middleware in front of every request: the ``Host`` must name this server;
    the websocket handshake needs the same-origin ``Origin`` and the secret (as the cookie the
    page got with it, or ``?secret=``); a page request carrying the secret sets that cookie."""
    from aiohttp import web

    @web.middleware
    async def guard(request, handler):
        host = request.host.lower()
        if served is not None and host not in served:
            raise web.HTTPMisdirectedRequest(text="unknown host\n")
        presented = request.query.get("secret")
        if request.path == ws_path:
            if request.headers.get("Origin", "").lower() != f"http://{host}":
                raise web.HTTPForbidden(text="origin refused\n")
            if not (_same(presented, secret) or _same(request.cookies.get(cookie), secret)):
                raise web.HTTPForbidden(text="secret refused\n")
            if len(clients()) >= MAX_CLIENTS:
                raise web.HTTPServiceUnavailable(text="too many connections\n")
            return await handler(request)
        response = await handler(request)
        if _same(presented, secret):
            response.set_cookie(cookie, secret, httponly=True, samesite="Strict", path="/")
        return response

    return guard


def _chunk_refusal(data, pending: dict) -> tuple[int, str] | None:
    """Why a wslink chunk is refused (close code, reason), or None. Checked on the header
    before wslink's un-chunker allocates the total size it declares."""
    from aiohttp import WSCloseCode

    if not isinstance(data, bytes | bytearray):
        return WSCloseCode.UNSUPPORTED_DATA, "binary wslink chunks only"
    if len(data) < _CHUNK_HEADER.size:
        return WSCloseCode.PROTOCOL_ERROR, "short chunk"
    mid, offset, total = _CHUNK_HEADER.unpack_from(data)
    if total > MAX_MESSAGE_BYTES:
        return WSCloseCode.MESSAGE_TOO_BIG, f"message larger than {MAX_MESSAGE_BYTES} bytes"
    if offset + len(data) - _CHUNK_HEADER.size > total:
        return WSCloseCode.PROTOCOL_ERROR, "chunk beyond its message"
    if mid not in pending and len(pending) >= MAX_PENDING_MESSAGES:
        return WSCloseCode.POLICY_VIOLATION, "too many unfinished messages"
    return None


def _harden(ws_handler, secret: str) -> None:
    """Shut wslink's websocket handler (its attributes are public): our secret instead of its
    public default, capped chunks, a connection that fails its hello closed, and only the
    controls' state keys accepted from the browser."""
    from aiohttp import WSCloseCode

    ws_handler.serverProtocol.updateSecret(secret)
    on_message = ws_handler.onMessage

    async def guarded(is_binary, msg, client_id):
        unchunker = ws_handler.unchunkers.get(client_id)
        pending = unchunker.pending_messages if unchunker is not None else {}
        why = _chunk_refusal(msg.data, pending) if is_binary else None
        if not is_binary:
            why = WSCloseCode.UNSUPPORTED_DATA, "binary wslink chunks only"
        if why is None:
            try:
                await on_message(is_binary, msg, client_id)
            except Exception:  # malformed msgpack, a chunk out of order, not an rpc
                why = WSCloseCode.PROTOCOL_ERROR, "malformed message"
            else:
                if not ws_handler.isClientAuthenticated(client_id) and not pending:
                    why = WSCloseCode.POLICY_VIOLATION, "authentication failed"
        ws = ws_handler.connections.get(client_id)
        if why is not None and ws is not None and not ws.closed:
            if unchunker is not None:
                unchunker.release_pending_messages()
            await ws.close(code=why[0], message=why[1].encode())

    ws_handler.onMessage = guarded
    uri = "trame.state.update"
    if uri in ws_handler.functionMap:
        protocol, update = ws_handler.functionMap[uri]

        def update_controls(obj, changes=None, *_, **__):
            # Only the controls' keys: no new keys (state that grows), no internal ones.
            if not isinstance(changes, list):
                return None
            keep = [c for c in changes if isinstance(c, dict) and c.get("key") in CONTROL_KEYS]
            return update(obj, keep) if keep else None

        ws_handler.functionMap[uri] = (protocol, update_controls)


def _secure(ws_server, *, host: str, port: int, secret: str) -> None:
    """``on_server_bind``: the wslink web server before it listens. Forces our address
    (whatever trame parsed), adds the guard in front of every route, hardens the websocket
    handlers."""
    config = ws_server.config
    if "reverse_url" in config or "ws" not in config:
        raise InputError("explore: trame was configured for a relay; refusing to start")
    config.update(host=host, port=port)
    config.pop("ssl", None)
    handlers = {}  # GET and HEAD routes share a handler
    for route in ws_server.app.router.routes():
        owner = getattr(route.handler, "__self__", None)
        if owner is not None and hasattr(owner, "unchunkers"):
            handlers[id(owner)] = owner
    handlers = list(handlers.values())
    ws_paths = [f"/{p.lstrip('/')}" for p in config["ws"]]
    if len(handlers) != 1 or len(ws_paths) != 1:
        raise InputError(f"explore: expected one websocket endpoint, got {ws_paths}")
    (handler,) = handlers
    _harden(handler, secret)
    served = _served_hosts(host, port)
    guard = _guard(secret, served, f"sciviz_gbuf_{port}", ws_paths[0], lambda: handler.connections)
    ws_server.app.middlewares.append(guard)


@contextlib.contextmanager
def _killable() -> Iterator[None]:
    """While a render or capture runs, the stop signals take their default action (the kernel
    ends the process at once): numba kernels and VTK hold the interpreter for the whole call,
    so no Python handler could run before it returns."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = {s: signal.signal(s, signal.SIG_DFL) for s in _STOP_SIGNALS}
    try:
        yield
    finally:
        for s, h in before.items():
            signal.signal(s, h)


def serve(explorer, *, port: int, secret: str, host: str = "127.0.0.1") -> None:
    """Serve ``explorer`` on ``host:port`` until a stop signal (or trame's idle timeout).

    The page is ``http://HOST:PORT/?secret=SECRET``. Nothing from the environment or
    ``sys.argv`` changes the address, the secret or the size caps (see the module docstring).

    Raises
    ------
    InputError
        The port cannot be listened on (in use, no permission) or ``host`` does not resolve.
    """
    server = build_app(explorer, port=port, busy=_killable)
    # trame reads its options from sys.argv and TRAME_ARGS (--host, --authKey, --ssl,
    # --reverse-url, ...): it gets its defaults and our values instead.
    options, _ = server.cli.parse_known_args([])
    options.host, options.port, options.authKey, options.authKeyFile = host, port, secret, None
    options.nosignalhandlers = True  # ours below: aiohttp's would wait for a busy render
    server.cli.parse_known_args = lambda *_, **__: (options, [])
    os.environ["WSLINK_MSG_OVERHEAD"] = "4096"  # frame cap = MAX_MESSAGE_BYTES + this
    server.controller.on_server_bind.add(
        lambda ws_server: _secure(ws_server, host=host, port=port, secret=secret)
    )

    def stop(signum, _frame) -> None:
        # Idle: the loop waits on its sockets (call_soon_threadsafe wakes it; call_soon would
        # wait for the next socket event). Close the connections and stop; a second signal
        # ends the process at once.
        for s in _STOP_SIGNALS:
            signal.signal(s, signal.SIG_DFL)
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:  # not serving yet
            sys.stdout.flush()
            os._exit(128 + signum)
        loop.call_soon_threadsafe(lambda: asyncio.ensure_future(server.stop()))

    for s in _STOP_SIGNALS:
        signal.signal(s, stop)
    try:
        server.start(
            host=host,
            port=port,
            open_browser=False,
            show_connection_info=False,
            disable_logging=True,
            backend="aiohttp",
            exec_mode="main",
        )
    except OSError as exc:  # the port was taken between check_port and now
        raise InputError(_port_message(host, port, exc)) from None
    finally:
        for s in _STOP_SIGNALS:
            signal.signal(s, signal.SIG_DFL)
