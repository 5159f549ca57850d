"""The explorer's server the way a user runs it (``python -m sciviz_gbuf explore`` in its own
process group), the URL it prints, and a bare wslink client over aiohttp's websocket client
for the protocol tests. Loopback addresses only; every wait has a deadline."""

from __future__ import annotations

import asyncio
import contextlib
import os
import queue
import re
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from tests.helpers.paths import PROJECT_ROOT

__all__ = [
    "Served",
    "free_port",
    "listening_addresses",
    "memory_kb",
    "served_explorer",
    "wslink_call",
    "wslink_chunk",
    "wslink_session",
]

_URL = re.compile(r"http://(?P<host>[^/\s]+)/\?secret=(?P<secret>[A-Za-z0-9_\-]+)")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def listening_addresses(port: int) -> list[str]:
    """Local addresses (hex, as the kernel lists them) of sockets listening on ``port``."""
    out = []
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            lines = Path(table).read_text().splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            parts = line.split()
            addr, p = parts[1].rsplit(":", 1)
            if int(p, 16) == port and parts[3] == "0A":  # 0A: LISTEN
                out.append(addr)
    return out


def memory_kb(pid: int) -> dict[str, int]:
    """``VmRSS`` and ``VmHWM`` (peak resident size) of a process, in kB."""
    out = {}
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        key, _, rest = line.partition(":")
        if key in ("VmRSS", "VmHWM"):
            out[key] = int(rest.split()[0])
    return out


@dataclass
class Served:
    """A running ``explore``: its process, port, printed URL and secret, and every line it has
    written so far (stdout and stderr together)."""

    proc: subprocess.Popen
    port: int
    url: str
    secret: str
    lines: list[str] = field(default_factory=list)

    @property
    def origin(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    @property
    def ws_url(self) -> str:
        return f"ws://127.0.0.1:{self.port}/ws"


@contextlib.contextmanager
def served_explorer(
    args: Sequence[str] = ("--size", "512x384"),
    *,
    port: int | None = None,
    env: dict[str, str] | None = None,
    timeout: float = 300.0,
) -> Iterator[Served]:
    """Start ``sciviz-gbuf explore --port PORT ARGS`` and wait (at most ``timeout`` s: the
    first run compiles numba kernels) until it printed its URL and answers HTTP."""
    port = free_port() if port is None else port
    full_env = dict(os.environ, PYTHONUNBUFFERED="1", **(env or {}))
    proc = subprocess.Popen(
        [sys.executable, "-m", "sciviz_gbuf", "explore", "--port", str(port), *args],
        cwd=PROJECT_ROOT,
        env=full_env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        start_new_session=True,  # its own process group: everything it starts ends with it
    )
    lines: queue.Queue[str | None] = queue.Queue()

    def pump() -> None:
        for raw in proc.stdout:
            lines.put(raw.decode(errors="replace").rstrip("\n"))
        lines.put(None)

    threading.Thread(target=pump, daemon=True).start()
    seen: list[str] = []
    try:
        deadline = time.monotonic() + timeout
        match = None
        while match is None:
            try:
                line = lines.get(timeout=max(0.1, deadline - time.monotonic()))
            except queue.Empty:
                line = ""
            if line is None:
                proc.wait(timeout=30)
                raise AssertionError(f"explore exited with {proc.returncode}:\n" + "\n".join(seen))
            if line:
                seen.append(line)
                match = _URL.search(line)
            if time.monotonic() > deadline:
                raise AssertionError("explore printed no URL in time:\n" + "\n".join(seen))
        while True:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=1) as r:
                    if r.status == 200:
                        break
            except OSError:
                pass
            if proc.poll() is not None or time.monotonic() > deadline:
                raise AssertionError(f"explore did not answer (rc {proc.poll()})")
            time.sleep(0.2)
        served = Served(proc, port, match.group(0), match.group("secret"), seen)

        def drain() -> None:  # keep collecting what it writes
            while (line := lines.get()) is not None:
                seen.append(line)

        threading.Thread(target=drain, daemon=True).start()
        yield served
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)


# -- a bare wslink client ---------------------------------------------------------------------


def wslink_chunk(obj: object, mid: int = 1) -> bytes:
    """One wslink chunk holding the whole msgpack message ``obj``."""
    import msgpack

    body = msgpack.packb(obj)
    return struct.pack("<III", mid, 0, len(body)) + body


def wslink_call(method: str, args: list, rpc_id: str) -> dict:
    return {"wslink": "1.0", "id": rpc_id, "method": method, "args": args, "kwargs": {}}


async def _messages(ws, seconds: float):
    """The wslink messages the server sends within ``seconds`` (single-chunk messages decoded;
    the loop ends at the deadline or when the socket closes)."""
    import aiohttp
    import msgpack

    parts: dict[int, bytearray] = {}
    deadline = time.monotonic() + seconds
    while (left := deadline - time.monotonic()) > 0:
        try:
            msg = await asyncio.wait_for(ws.receive(), left)
        except asyncio.TimeoutError:
            return
        if msg.type != aiohttp.WSMsgType.BINARY:
            yield msg
            return
        mid, offset, total = struct.unpack_from("<III", msg.data)
        buf = parts.setdefault(mid, bytearray(total))
        body = msg.data[12:]
        buf[offset : offset + len(body)] = body
        if offset + len(body) >= total:
            del parts[mid]
            yield msgpack.unpackb(bytes(buf))


@contextlib.asynccontextmanager
async def wslink_session(served: Served, *, secret: str | None = None, hello: bool = True):
    """An aiohttp websocket to the explorer (same-origin, ``?secret=``), after a successful
    wslink hello unless ``hello`` is False; yields ``(ws, messages)`` where
    ``messages(seconds)`` iterates over what the server sends."""
    import aiohttp

    secret = served.secret if secret is None else secret
    async with aiohttp.ClientSession() as session:
        async with session.ws_connect(
            f"{served.ws_url}?secret={served.secret}", origin=served.origin
        ) as ws:
            if hello:
                await ws.send_bytes(
                    wslink_chunk(wslink_call("wslink.hello", [{"secret": secret}], "system:c0:0"))
                )
                async for m in _messages(ws, 30.0):
                    assert isinstance(m, dict) and "result" in m, m
                    break
            yield ws, lambda seconds: _messages(ws, seconds)
