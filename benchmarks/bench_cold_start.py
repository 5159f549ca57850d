"""Benchmark: the first run after an install, when numba compiles every kernel it calls.

Run from the project root with the project's venv active::

    python benchmarks/bench_cold_start.py                 # cold demo and topo, ~8 min here
    python benchmarks/bench_cold_start.py --only topo     # one of them
    python benchmarks/bench_cold_start.py --top 25        # longer list of compiles

What is measured, each in a fresh process with ``NUMBA_CACHE_DIR`` pointing at an empty folder
(numba finds no cached kernel: what a user's first run pays): ``sciviz-gbuf demo`` at its
default size into a temporary folder, and ``sciviz-gbuf topo`` of the bundled Jacksboro DEM.
Then the same commands once more with that cache (warm). The child process records numba's
``numba:compile`` events (``numba.core.event``): the compile share of the cold run and the
kernels that took longest, each with its own compile time (a kernel's time includes the
functions compiled inside it the first time). Goals of issue "First hour of a new user": a cold
demo <= 60 s and a cold topo <= 20 s on this 2-core machine.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

_CHILD = r"""
import json, sys, time
from numba.core import event

events = []
depth = [0]

class _Rec(event.Listener):
    def on_start(self, ev):
        ev.data["t0"] = time.perf_counter()
        ev.data["depth"] = depth[0]
        depth[0] += 1

    def on_end(self, ev):
        depth[0] -= 1
        d = ev.data
        name = getattr(d.get("dispatcher"), "__qualname__", None) or str(d.get("dispatcher"))
        mod = getattr(getattr(d.get("dispatcher"), "py_func", None), "__module__", "")
        events.append((f"{mod}.{name}", time.perf_counter() - d["t0"], d["depth"]))

event.register("numba:compile", _Rec())
from sciviz_gbuf.cli import main
t0 = time.perf_counter()
rc = main(sys.argv[2:])
wall = time.perf_counter() - t0
with open(sys.argv[1], "w") as f:
    json.dump({"rc": rc, "wall": wall, "events": events}, f)
"""


def run(cmd: list[str], cache: str, second: bool = True) -> dict:
    """One command in a fresh interpreter with ``cache`` as numba's cache; its record, with
    the seconds to the first line on stderr (``first``: the command's --progress)."""
    with tempfile.NamedTemporaryFile(suffix=".json", delete=False) as f:
        out = f.name
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    env.pop("SCIVIZ_GBUF_NO_WARMUP", None)
    if not second:
        env["SCIVIZ_GBUF_NO_WARMUP"] = "1"  # no second process compiling on the other core
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-c", _CHILD, out, *cmd],
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    first = None
    err = []
    for line in proc.stderr:
        if first is None:
            first = time.perf_counter() - t0
        err.append(line)
    rc = proc.wait()
    total = time.perf_counter() - t0
    if rc != 0:
        raise SystemExit(f"{' '.join(cmd)} failed: {''.join(err).strip()[-500:]}")
    with open(out) as f:
        rec = json.load(f)
    os.unlink(out)
    rec["total"] = total  # with the interpreter start and the imports
    rec["first"] = first
    return rec


def _outermost(events: list) -> float:
    """Compile seconds, nested compiles (a kernel's callees, compiled inside it the first
    time) counted once: the sum over the outermost events."""
    return sum(dt for _, dt, depth in events if depth == 0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--only", choices=["demo", "topo"], default=None)
    ap.add_argument("--top", type=int, default=12)
    args = ap.parse_args()
    work = tempfile.mkdtemp(prefix="sciviz_cold_")
    jobs = {
        "demo": ["demo", "-o", os.path.join(work, "demo"), "--progress"],
        "topo": ["topo", "-o", os.path.join(work, "topo.png"), "--progress"],
    }
    if args.only:
        jobs = {args.only: jobs[args.only]}
    goals = {"demo": 60.0, "topo": 20.0}
    head = ["cold s", "1st line", "compile", "share", "1 proc s", "2 vs 1", "warm s", "cold/warm"]
    print(f"{'command':8s} " + " ".join(f"{h:>8s}" for h in [*head, "goal s"]))
    tops = {}
    for name, cmd in jobs.items():
        cache = tempfile.mkdtemp(prefix="numba_", dir=work)
        cold = run(cmd, cache)
        warm = run(cmd, cache)
        alone = run(cmd, tempfile.mkdtemp(prefix="numba_", dir=work), second=False)
        comp = _outermost(cold["events"])
        print(
            f"{name:8s} {cold['total']:8.1f} {cold['first'] or float('nan'):8.2f} {comp:8.1f} "
            f"{comp / cold['total']:8.0%} {alone['total']:8.1f} "
            f"{cold['total'] / alone['total']:8.2f} {warm['total']:8.1f} "
            f"{cold['total'] / warm['total']:8.1f} {goals[name]:8.0f}"
        )
        per: dict[str, float] = {}
        for fn, dt, _ in alone["events"]:
            per[fn] = per.get(fn, 0.0) + dt
        tops[name] = sorted(per.items(), key=lambda kv: -kv[1])[: args.top]
    print("cold / 1 proc / warm: the whole process (interpreter, imports, the command), cold")
    print("with the second process compiling on the other core (apps.warmup), 1 proc without;")
    print("1st line: seconds to the first line on stderr; compile: the numba:compile events of")
    print("the cold run's own process, nested ones counted once")
    for name, top in tops.items():
        print(f"\nlongest compiles of the cold {name}, one process (s, all signatures, callees"
              " included):")  # fmt: skip
        for fn, dt in top:
            print(f"  {dt:7.1f}  {fn}")
    print(json.dumps({"work": work}))


if __name__ == "__main__":
    main()
