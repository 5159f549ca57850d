"""Running ``sciviz-gbuf`` the way a user does (a fresh process, no stdin) and checking how it
fails: exit status 2, one line on stderr naming the file or parameter, no traceback, no signal
death, no output file (or temporary) left behind, inputs unmodified."""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from collections.abc import Iterable, Sequence
from pathlib import Path

__all__ = ["assert_clean_failure", "checksums", "run_cli"]


def run_cli(
    args: Sequence[str | os.PathLike],
    *,
    cwd: str | os.PathLike | None = None,
    timeout: float = 300.0,
    env: dict[str, str] | None = None,
) -> subprocess.CompletedProcess:
    """``python -m sciviz_gbuf ARGS`` in a subprocess (stdin closed, output captured)."""
    full_env = {**os.environ, **(env or {})}
    return subprocess.run(
        [sys.executable, "-m", "sciviz_gbuf", *map(str, args)],
        cwd=cwd,
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        errors="replace",
        timeout=timeout,
        env=full_env,
    )


def checksums(paths: Iterable[str | os.PathLike]) -> dict[str, str]:
    """SHA-256 of every file under ``paths`` (files or folders), by path."""
    out = {}
    for p in map(Path, paths):
        files = sorted(f for f in p.rglob("*") if f.is_file()) if p.is_dir() else [p]
        for f in files:
            if f.exists():
                out[str(f)] = hashlib.sha256(f.read_bytes()).hexdigest()
    return out


def assert_clean_failure(
    proc: subprocess.CompletedProcess,
    *,
    names: str | os.PathLike | Sequence[str | os.PathLike],
    outputs: Sequence[str | os.PathLike] = (),
    inputs: dict[str, str] | None = None,
) -> str:
    """The process refused its input cleanly; returns the error line.

    Parameters
    ----------
    names : the file or parameter (any of several) the message must name.
    outputs : files that must not exist afterwards; their folders must hold no temporaries.
    inputs : :func:`checksums` of the inputs before the run; they must be unchanged.
    """
    err = proc.stderr.strip()
    where = f"rc={proc.returncode}\nstdout: {proc.stdout[-2000:]}\nstderr: {proc.stderr[-4000:]}"
    assert proc.returncode == 2, where
    assert "Traceback" not in proc.stderr and "Traceback" not in proc.stdout, where
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, where
    wanted = [names] if isinstance(names, (str, os.PathLike)) else list(names)
    assert any(str(n) in lines[0] for n in wanted), where
    for out in map(Path, outputs):
        assert not out.exists(), f"{out} was left behind\n{where}"
        if out.parent.is_dir():
            stray = [p.name for p in out.parent.iterdir() if p.name.startswith(f".{out.name}")]
            assert not stray, f"temporaries left: {stray}\n{where}"
    if inputs is not None:
        assert checksums(inputs) == inputs, f"an input was modified\n{where}"
    return lines[0]
