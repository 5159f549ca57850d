"""The explorer is no open door: the real server in a subprocess on a free loopback port, a
real websocket client (aiohttp) and hand-made frames on a raw socket.

Refused: a foreign Origin or Host, a missing or wrong secret (wslink's public default among
them), an oversized websocket frame and a wslink chunk declaring 2 GiB (without the server's
memory growing), state values beyond the Python API's bounds (put back to the last good value),
state keys that are no control. SIGTERM ends a busy server at once and an idle one cleanly;
``--port 70000``, a port in use or an unresolvable ``--host`` fail with one line, exit 2."""

from __future__ import annotations

import asyncio
import base64
import contextlib
import dataclasses
import math
import os
import signal
import socket
import struct
import subprocess
import time
import urllib.error
import urllib.request

import pytest

from sciviz_gbuf._validate import LIMITS
from sciviz_gbuf.apps.explorer import CAMERA_BOUNDS, PARAM_BOUNDS, Explorer, Params
from sciviz_gbuf.apps.explorer_web import MAX_CLIENTS, MAX_MESSAGE_BYTES
from sciviz_gbuf.datasets import load_nut
from sciviz_gbuf.errors import InputError
from tests.apps.explorer_server import (
    free_port,
    listening_addresses,
    memory_kb,
    served_explorer,
    wslink_call,
    wslink_chunk,
    wslink_session,
)
from tests.helpers.cli import assert_clean_failure, run_cli

pytest.importorskip("trame")
pytest.importorskip("trame_vuetify")
aiohttp = pytest.importorskip("aiohttp")

#: What the attacks may add to the server's resident size and its peak (the issue's frames
#: made it allocate 2 GiB each).
GROWTH_KB = 100 * 1024
GIB2 = 2**31


@pytest.fixture(scope="module")
def server():
    with served_explorer(("--size", "256x192")) as served:
        # A first authenticated update, so that what the attacks are measured against
        # includes a warm server (its first render, the JPEG encoder, a client's buffers).
        asyncio.run(_set_state(served, {"light_azimuth": 130.0}))
        served.baseline = memory_kb(served.proc.pid)
        yield served
        assert served.proc.poll() is None, "the server died during the tests"


def _assert_memory_bounded(served) -> dict[str, int]:
    now = memory_kb(served.proc.pid)
    for key in ("VmRSS", "VmHWM"):
        assert now[key] - served.baseline[key] < GROWTH_KB, (key, served.baseline, now)
    return now


async def _set_state(served, values: dict, seconds: float = 8.0, until=None) -> dict:
    """Send a state update as the page does; returns the state keys the server published
    back within ``seconds`` (merged), or as soon as ``until(seen)`` holds."""
    changes = [{"key": k, "value": v} for k, v in values.items()]
    seen: dict = {}
    async with wslink_session(served) as (ws, messages):
        await ws.send_bytes(
            wslink_chunk(wslink_call("trame.state.update", [changes], "rpc:c0:1"), mid=2)
        )
        async for m in messages(seconds):
            if isinstance(m, dict) and str(m.get("id", "")).startswith("publish:trame.state"):
                seen.update(m["result"])
                if until is not None and until(seen):
                    break
    return seen


async def _handshake_status(served, *, origin, secret, headers=None) -> int:
    """HTTP status of a websocket handshake (101 when accepted)."""
    url = served.ws_url + (f"?secret={secret}" if secret is not None else "")
    async with aiohttp.ClientSession() as session:
        try:
            async with session.ws_connect(url, origin=origin, headers=headers or {}):
                return 101
        except aiohttp.WSServerHandshakeError as exc:
            return exc.status


# -- the handshake ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "origin",
    [
        "http://evil.example",
        "https://127.0.0.1",
        "http://127.0.0.1",  # another port is another origin
        "http://127.0.0.1:1",
        "null",
        None,  # no Origin at all (not a browser)
    ],
)
def test_foreign_origin_is_refused(server, origin):
    if origin == "http://127.0.0.1:1" and server.port == 1:  # pragma: no cover
        pytest.skip("port clash")
    status = asyncio.run(_handshake_status(server, origin=origin, secret=server.secret))
    assert status == 403
    _assert_memory_bounded(server)


def test_same_origin_with_the_secret_is_accepted(server):
    for origin in (server.origin, f"http://localhost:{server.port}"):
        host = origin.removeprefix("http://")
        status = asyncio.run(
            _handshake_status(server, origin=origin, secret=server.secret, headers={"Host": host})
        )
        assert status == 101, origin


def test_dns_rebinding_host_is_refused(server):
    # A page of evil.example whose name now resolves to 127.0.0.1: same "origin" as its Host.
    host = f"evil.example:{server.port}"
    status = asyncio.run(
        _handshake_status(
            server, origin=f"http://{host}", secret=server.secret, headers={"Host": host}
        )
    )
    assert status == 421
    req = urllib.request.Request(f"http://127.0.0.1:{server.port}/", headers={"Host": host})
    with pytest.raises(urllib.error.HTTPError) as err:
        urllib.request.urlopen(req, timeout=10)
    assert err.value.code == 421


@pytest.mark.parametrize(
    "secret", [None, "", "wslink-secret", "x", "A" * 43, "%00", "é", "S" * 5000]
)
def test_missing_or_wrong_secret_is_refused_at_the_handshake(server, secret):
    status = asyncio.run(_handshake_status(server, origin=server.origin, secret=secret))
    assert status == 403
    _assert_memory_bounded(server)


def test_the_page_request_with_the_secret_sets_the_cookie_the_websocket_needs(server):
    async def run() -> tuple[int, int]:
        jar = aiohttp.CookieJar(unsafe=True)  # cookies for an IP address
        async with aiohttp.ClientSession(cookie_jar=jar) as session:
            async with session.get(f"{server.origin}/index.html?secret=wrong") as r:
                assert r.status == 200
            try:
                async with session.ws_connect(server.ws_url, origin=server.origin):
                    without = 101
            except aiohttp.WSServerHandshakeError as exc:
                without = exc.status
            async with session.get(f"{server.origin}/?secret={server.secret}") as r:
                assert r.status == 200  # after the redirect to index.html
            async with session.ws_connect(server.ws_url, origin=server.origin):
                return without, 101

    assert asyncio.run(run()) == (403, 101)


@pytest.mark.parametrize("secret", ["wslink-secret", "", "wrong", None])
def test_wrong_secret_in_the_hello_closes_the_connection(server, secret):
    async def run():
        async with wslink_session(server, hello=False) as (ws, messages):
            args = [{"secret": secret}] if secret is not None else []
            await ws.send_bytes(wslink_chunk(wslink_call("wslink.hello", args, "system:c0:0")))
            got = [m async for m in messages(10.0)]
            # Then an rpc without authentication gets nowhere: the socket is closed.
            return got, ws.closed, ws.close_code

    got, closed, code = asyncio.run(run())
    assert any(isinstance(m, dict) and "error" in m for m in got), got
    assert closed and code == aiohttp.WSCloseCode.POLICY_VIOLATION


def test_connections_are_capped(server):
    async def run() -> int:
        async with aiohttp.ClientSession() as session:
            url = f"{server.ws_url}?secret={server.secret}"
            opened = [
                await session.ws_connect(url, origin=server.origin) for _ in range(MAX_CLIENTS)
            ]
            try:
                async with session.ws_connect(url, origin=server.origin):
                    return 101
            except aiohttp.WSServerHandshakeError as exc:
                return exc.status
            finally:
                for ws in opened:
                    await ws.close()

    assert asyncio.run(run()) == 503
    time.sleep(0.5)  # the server forgets the closed ones
    assert asyncio.run(_handshake_status(server, origin=server.origin, secret=server.secret)) == 101


# -- oversized frames -------------------------------------------------------------------------


def _raw_handshake(served) -> socket.socket:
    """A raw socket after an accepted websocket handshake (no compression offered)."""
    s = socket.create_connection(("127.0.0.1", served.port), timeout=20)
    key = base64.b64encode(os.urandom(16)).decode()
    s.sendall(
        (
            f"GET /ws?secret={served.secret} HTTP/1.1\r\nHost: 127.0.0.1:{served.port}\r\n"
            f"Upgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
            f"Sec-WebSocket-Version: 13\r\nOrigin: {served.origin}\r\n\r\n"
        ).encode()
    )
    head = b""
    while b"\r\n\r\n" not in head:
        part = s.recv(4096)
        assert part, head
        head += part
    assert head.split(b"\r\n", 1)[0].split()[1] == b"101", head
    return s


def _frame_header(length: int, opcode: int = 0x2) -> bytes:
    """A client frame header (FIN, masked) declaring ``length`` payload bytes."""
    mask = os.urandom(4)
    if length < 126:
        return bytes([0x80 | opcode, 0x80 | length]) + mask
    if length < 2**16:
        return bytes([0x80 | opcode, 0x80 | 126]) + struct.pack(">H", length) + mask
    return bytes([0x80 | opcode, 0x80 | 127]) + struct.pack(">Q", length) + mask


def _close_code(s: socket.socket) -> int | None:
    """The close code of the server's close frame, None if the socket just ended."""
    data = b""
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        try:
            part = s.recv(65536)
        except (ConnectionResetError, TimeoutError):
            break
        if not part:
            break
        data += part
        while len(data) >= 2:
            opcode, n = data[0] & 0x0F, data[1] & 0x7F
            at = 2 if n < 126 else (4 if n == 126 else 10)
            if n >= 126:
                n = struct.unpack(">H" if at == 4 else ">Q", data[2:at])[0]
            if len(data) < at + n:
                break
            if opcode == 0x8:
                return struct.unpack(">H", data[at : at + 2])[0]
            data = data[at + n :]
    return None


def test_frame_declaring_2_gib_is_refused_without_allocating(server):
    before = memory_kb(server.proc.pid)
    for _ in range(3):  # the three frames: 6.6 GB
        with _raw_handshake(server) as s:
            s.sendall(_frame_header(GIB2) + b"\x00" * 64)
            assert _close_code(s) == aiohttp.WSCloseCode.MESSAGE_TOO_BIG
    after = _assert_memory_bounded(server)
    assert after["VmHWM"] - before["VmHWM"] < GROWTH_KB


def test_frame_just_over_the_cap_is_refused(server):
    with _raw_handshake(server) as s:
        s.sendall(_frame_header(MAX_MESSAGE_BYTES + 4096 + 1))
        assert _close_code(s) == aiohttp.WSCloseCode.MESSAGE_TOO_BIG


@pytest.mark.parametrize("authenticated", [False, True])
def test_wslink_chunk_declaring_2_gib_is_refused_without_allocating(server, authenticated):
    """The issue's 25-byte frame: a chunk header declaring a 2 GiB message (wslink allows 4 GB
    once a client is authenticated)."""

    async def run() -> list:
        codes = []
        for mid in (7, 8, 9):
            async with wslink_session(server, hello=authenticated) as (ws, messages):
                await ws.send_bytes(struct.pack("<III", mid, 0, GIB2) + b"\x00" * 13)
                _ = [m async for m in messages(10.0)]
                codes.append(ws.close_code)
        return codes

    before = memory_kb(server.proc.pid)
    assert asyncio.run(run()) == [aiohttp.WSCloseCode.MESSAGE_TOO_BIG] * 3
    after = _assert_memory_bounded(server)
    assert after["VmHWM"] - before["VmHWM"] < GROWTH_KB


@pytest.mark.parametrize(
    "chunk, closes",
    [
        (b"", True),  # empty
        (b"\x01\x00", True),  # shorter than the header
        (struct.pack("<III", 1, 900, 10) + b"x" * 10, True),  # beyond its message
        (struct.pack("<III", 1, 0, 4) + b"\xc1\xc1\xc1\xc1", True),  # not msgpack
        (wslink_chunk({"id": "rpc:c0:9"}), True),  # an rpc without a method
        (wslink_chunk([1, 2, 3]), False),  # msgpack, not an rpc: wslink ignores it
    ],
)
def test_malformed_chunks_are_refused_quietly(server, chunk, closes):
    async def run():
        async with wslink_session(server) as (ws, messages):
            await ws.send_bytes(chunk)
            _ = [m async for m in messages(5.0)]
            # (a receive that times out marks the code 1006 on the client's side only)
            return ws.closed, ws.close_code

    closed, code = asyncio.run(run())
    assert closed == closes
    if closes:
        assert code == aiohttp.WSCloseCode.PROTOCOL_ERROR
    assert server.proc.poll() is None
    assert not any("Traceback" in line for line in server.lines), server.lines[-20:]
    _assert_memory_bounded(server)


def test_unfinished_messages_are_capped(server):
    async def run():
        async with wslink_session(server) as (ws, messages):
            for mid in range(100, 140):  # each declares 1 MiB and sends 13 bytes
                try:
                    await ws.send_bytes(
                        struct.pack("<III", mid, 0, MAX_MESSAGE_BYTES) + b"\x00" * 13
                    )
                except (ConnectionError, aiohttp.ClientError):
                    break  # closed by the server
            _ = [m async for m in messages(10.0)]
            return ws.close_code

    assert asyncio.run(run()) == aiohttp.WSCloseCode.POLICY_VIOLATION
    _assert_memory_bounded(server)


def test_text_messages_are_refused(server):
    async def run():
        async with wslink_session(server) as (ws, messages):
            await ws.send_str("x" * 1000)
            _ = [m async for m in messages(10.0)]
            return ws.close_code

    assert asyncio.run(run()) == aiohttp.WSCloseCode.UNSUPPORTED_DATA


# -- state values -----------------------------------------------------------------------------


def _beyond(name: str) -> list:
    low, high, strict, integer = PARAM_BOUNDS[name]
    out = [high * 2 + 1, -abs(low) - 1e9, math.nan, math.inf, "5", [1], True, None]
    if strict:
        out.append(low)
    if integer:
        out.append(low + 0.5)
    return out


@pytest.mark.parametrize(
    "name, value",
    [
        ("width", 5000),
        ("map_bands", 1e8),
        ("bands", 10**8),
        ("contour_width", 1e4),
        ("map_width", 1e3),
        ("major_every", 10**7),
        ("crease_angle", -1),
        ("style", "x" * 100_000),  # a long value: the message stays short
        ("view", {"nested": [1, 2, 3]}),
        ("contour_interval", 1e-30),  # 10^31 lines over the nut's heights
    ],
)
def test_out_of_range_state_is_refused_through_the_protocol(server, name, value):
    good = getattr(Params(), name)

    def refused(seen: dict) -> bool:  # put back and told; else wait the full time
        return seen.get(name) == good and name in seen.get("error", "")

    seen = asyncio.run(_set_state(server, {name: value}, until=refused))
    assert seen.get(name) == good, seen  # put back to the last good value
    assert name in seen.get("error", name), seen  # (unchanged if already shown)
    assert len(seen.get("error", "")) <= 300
    _assert_memory_bounded(server)


def test_state_keys_that_are_no_control_are_dropped(server):
    async def run():
        async with wslink_session(server) as (ws, messages):
            changes = [{"key": f"junk{i}", "value": "x" * 1000} for i in range(200)]
            changes.append({"key": "image_url", "value": "javascript:alert(1)"})
            await ws.send_bytes(
                wslink_chunk(wslink_call("trame.state.update", [changes], "rpc:c0:1"), mid=2)
            )
            _ = [m async for m in messages(3.0)]
            await ws.send_bytes(wslink_chunk(wslink_call("trame.state.get", [], "rpc:c0:2"), mid=3))
            async for m in messages(20.0):
                if isinstance(m, dict) and m.get("id") == "rpc:c0:2":
                    return m["result"]["state"]
        return None

    state = asyncio.run(run())
    assert state is not None
    assert not any(k.startswith("junk") for k in state)
    assert state["image_url"].startswith("data:image/jpeg;base64,")


def test_a_good_value_still_updates(server):
    seen = asyncio.run(_set_state(server, {"width": 2.0}, until=lambda seen: "update_ms" in seen))
    assert "update_ms" in seen and seen.get("error", "") == ""


@pytest.fixture(scope="module")
def small_explorer() -> Explorer:
    return Explorer(load_nut(), window_size=(64, 48))


@pytest.mark.parametrize("name, value", [(n, v) for n in PARAM_BOUNDS for v in _beyond(n)], ids=str)
def test_every_parameter_is_bounded_in_process(small_explorer, name, value):
    e = small_explorer
    before = e.params
    with pytest.raises(InputError, match=name) as err:
        e.render_image({name: value})
    assert "\n" not in str(err.value) and len(str(err.value)) < 300
    assert e.params == before  # left unchanged


@pytest.mark.parametrize("name", list(PARAM_BOUNDS))
def test_every_bound_itself_is_accepted(name):
    low, high, strict, _ = PARAM_BOUNDS[name]
    Params(**{name: high}).checked()
    if not strict:
        Params(**{name: low}).checked()


def test_bounds_are_those_of_the_python_api():
    assert PARAM_BOUNDS["width"][1] == LIMITS["line_width"]
    assert PARAM_BOUNDS["contour_width"][1] == LIMITS["line_width"]
    assert PARAM_BOUNDS["map_width"][1] * 2 == LIMITS["line_width"]  # majors: twice as wide
    assert PARAM_BOUNDS["bands"][1] == PARAM_BOUNDS["map_bands"][1] == LIMITS["bands"]
    assert PARAM_BOUNDS["major_every"][1] == LIMITS["levels"]
    # Every numeric field of Params has a bound.
    numeric = {f.name for f in dataclasses.fields(Params)} - {"style", "view", "relief"}
    assert numeric == set(PARAM_BOUNDS)


@pytest.mark.parametrize(
    "name, value",
    [("zoom", 0.0), ("zoom", 1e9), ("zoom", math.nan), ("elevation", 91.0),
     ("azimuth", 1e12), ("azimuth", "45"), ("elevation", [30])],
)  # fmt: skip
def test_camera_is_bounded(small_explorer, name, value):
    e = small_explorer
    before = dataclasses.replace(e.camera)
    kwargs = {"azimuth": 0.0, "elevation": 30.0, "zoom": 1.0, name: value}
    with pytest.raises(InputError, match=name):
        e.set_camera(**kwargs)
    assert e.camera == before
    assert set(CAMERA_BOUNDS) == {"azimuth", "elevation", "zoom"}


def test_window_size_is_bounded():
    side = int(LIMITS["image_side"])
    with pytest.raises(InputError, match="--size"):
        Explorer(load_nut(), window_size=(side + 1, 16))


def test_interval_drawing_too_many_lines_is_refused(small_explorer):
    e = small_explorer
    lo, hi = e.height_range
    with pytest.raises(InputError, match="contour_interval"):
        e.render_image({"contour_interval": (hi - lo) / (LIMITS["levels"] * 10)})


# -- address, environment, signals, port ------------------------------------------------------


def test_trame_args_and_environment_do_not_move_the_server():
    env = {
        "TRAME_ARGS": "--host 0.0.0.0 --port 9 --authKey wslink-secret --timeout 1",
        "TRAME_DEFAULT_HOST": "0.0.0.0",
        "TRAME_BACKEND": "generic",
        "TRAME_WS_MAX_MSG_SIZE": str(2**33),
        "WSLINK_MSG_OVERHEAD": str(2**33),
    }
    with served_explorer(("--size", "64x48"), env=env) as served:
        assert listening_addresses(served.port) == ["0100007F"]  # 127.0.0.1 only
        assert (
            asyncio.run(_handshake_status(served, origin=served.origin, secret="wslink-secret"))
            == 403
        )
        with _raw_handshake(served) as s:
            s.sendall(_frame_header(GIB2))
            assert _close_code(s) == aiohttp.WSCloseCode.MESSAGE_TOO_BIG
        assert served.url.startswith(f"http://127.0.0.1:{served.port}/?secret=")


def test_explicit_host_warns_on_one_line():
    with served_explorer(("--size", "64x48", "--host", "0.0.0.0")) as served:
        warnings = [ln for ln in served.lines if "warning" in ln]
        assert len(warnings) == 1 and "--host 0.0.0.0" in warnings[0], served.lines
        assert listening_addresses(served.port) == ["00000000"]  # what was asked for
        # Still only with the secret and from the same origin.
        assert asyncio.run(_handshake_status(served, origin=served.origin, secret=None)) == 403


def test_sigterm_while_busy_ends_the_process_at_once():
    # 2048^2 with 64-pixel lines: one update keeps the server in numba for many seconds.
    with served_explorer(("--size", "2048x2048")) as served:

        async def terminate_during_a_heavy_update() -> None:
            async with wslink_session(served) as (ws, _):
                changes = [{"key": "width", "value": 64.0}, {"key": "crease_angle", "value": 5.0}]
                await ws.send_bytes(
                    wslink_chunk(wslink_call("trame.state.update", [changes], "rpc:c0:1"), 2)
                )
                await asyncio.sleep(2.0)  # the render has started
                os.kill(served.proc.pid, signal.SIGTERM)

        with contextlib.suppress(ConnectionError, aiohttp.ClientError, asyncio.TimeoutError):
            asyncio.run(terminate_during_a_heavy_update())
        try:
            rc = served.proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            pytest.fail("explore ignored SIGTERM while busy")
        # Killed by the signal itself (its default action during a render), not after it.
        assert rc == -signal.SIGTERM, served.lines


def test_sigterm_when_idle_stops_cleanly():
    with served_explorer(("--size", "64x48")) as served:
        os.kill(served.proc.pid, signal.SIGTERM)
        try:
            rc = served.proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            pytest.fail("explore ignored SIGTERM")
        assert rc == 0, served.lines
        assert not any("Traceback" in ln for ln in served.lines), served.lines


@pytest.mark.parametrize("port", ["70000", "0", "-1", "abc", "8080.5", ""])
def test_bad_port_fails_with_one_line(port):
    proc = run_cli(["explore", "--port", port])
    line = assert_clean_failure(proc, names="--port")
    assert "65535" in line


def test_port_in_use_fails_with_one_line_naming_it():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        proc = run_cli(["explore", "--port", str(port)])
    line = assert_clean_failure(proc, names=str(port))
    assert "in use" in line


def test_unresolvable_host_fails_with_one_line():
    proc = run_cli(["explore", "--host", "no-such-host.invalid", "--port", str(free_port())])
    assert_clean_failure(proc, names="--host")
