"""Many CLI runs without paying the interpreter's start-up each time: a warm server process
that has imported the package, VTK and PyVista forks a child per run.

A child is a process of its own (its exit status, a signal that kills it, its stdin closed,
its stdout and stderr captured), running ``sciviz_gbuf.cli.main`` as ``python -m sciviz_gbuf``
does, in its own working directory, so a crash or a hang of one run is seen as such. What it
does not repeat is the ~1.3 s of imports every fresh ``python -m sciviz_gbuf`` spends before
its first line of work (tests that are about start-up itself use :func:`.cli.run_cli`).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import threading
from collections.abc import Sequence
from pathlib import Path

from .paths import PROJECT_ROOT

# The server: read one JSON request a line, fork, answer one JSON line when the child ends.
_SERVER = r"""
import json, os, sys, time, traceback
import importlib
import pyvista, vtk  # noqa: F401  (what the mesh commands import: loaded once, before forks)
from sciviz_gbuf import cli
for name in ("sciviz_gbuf.core.capture", "sciviz_gbuf.readers", "sciviz_gbuf.recipes.npr",
             "sciviz_gbuf.recipes.vector", "sciviz_gbuf.styles", "scipy.ndimage"):
    importlib.import_module(name)  # what the commands import lazily, also loaded once

def child(req):
    os.chdir(req["cwd"])
    for fd, path, flags in ((0, os.devnull, os.O_RDONLY),
                            (1, req["stdout"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC),
                            (2, req["stderr"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC)):
        f = os.open(path, flags, 0o644)
        os.dup2(f, fd)
        os.close(f)
    sys.argv = ["sciviz-gbuf", *req["args"]]
    try:
        code = cli.main(req["args"])
    except SystemExit as e:  # what the interpreter does with it at exit
        code = e.code
        if code is not None and not isinstance(code, int):
            print(code, file=sys.stderr)
            code = 1
    except BaseException:
        traceback.print_exc()
        code = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0 if code is None else int(code) & 0xFF)

out = sys.stdout
for line in sys.stdin:
    req = json.loads(line)
    pid = os.fork()
    if pid == 0:
        try:
            child(req)
        finally:
            os._exit(120)
    deadline = time.monotonic() + req["timeout"]
    timed_out = False
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        if time.monotonic() > deadline:
            os.kill(pid, 9)
            _, status = os.waitpid(pid, 0)
            timed_out = True
            break
        time.sleep(0.005)
    out.write(json.dumps({"returncode": os.waitstatus_to_exitcode(status),
                          "timeout": timed_out}) + "\n")
    out.flush()
"""


class ForkCli:
    """A warm server of CLI runs; :meth:`run` is :func:`.cli.run_cli` in a forked child.
    One run at a time per server (a lock); use one server per worker thread."""

    def __init__(self, env: dict[str, str] | None = None) -> None:
        self._lock = threading.Lock()
        self._tmp = tempfile.TemporaryDirectory(prefix="fork_cli_")
        self._n = 0
        self._proc = subprocess.Popen(
            [sys.executable, "-c", _SERVER],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
            cwd=PROJECT_ROOT,
            env={**os.environ, **(env or {})},
        )

    def run(
        self, args: Sequence[str | os.PathLike], *, cwd: str | os.PathLike, timeout: float = 300.0
    ) -> subprocess.CompletedProcess:
        with self._lock:
            self._n += 1
            out = Path(self._tmp.name) / f"{self._n}.out"
            err = Path(self._tmp.name) / f"{self._n}.err"
            req = {"args": [str(a) for a in args], "cwd": str(Path(cwd).resolve()),
                   "stdout": str(out), "stderr": str(err), "timeout": float(timeout)}  # fmt: skip
            assert self._proc.stdin is not None and self._proc.stdout is not None
            self._proc.stdin.write(json.dumps(req) + "\n")
            self._proc.stdin.flush()
            line = self._proc.stdout.readline()
            if not line:
                raise RuntimeError("the fork server ended (its imports failed?)")
            reply = json.loads(line)
            if reply["timeout"]:
                raise subprocess.TimeoutExpired(["sciviz-gbuf", *req["args"]], timeout)
            read = lambda p: p.read_text(errors="replace") if p.exists() else ""  # noqa: E731
            return subprocess.CompletedProcess(
                ["sciviz-gbuf", *req["args"]], reply["returncode"], read(out), read(err)
            )

    def close(self) -> None:
        if self._proc.poll() is None:
            assert self._proc.stdin is not None
            self._proc.stdin.close()
            try:
                self._proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        self._tmp.cleanup()

    def __enter__(self) -> ForkCli:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
