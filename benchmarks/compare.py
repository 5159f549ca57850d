"""Base against head on one machine, in one run: every headline benchmark's ratio.

The way NumPy, SciPy and scikit-image guard their speed with ``asv continuous``, without asv's
per-commit environments (each would build VTK, numba and GDAL wheels anew): both trees run in
this venv, the base from a ``git worktree`` of the base commit and the head from the project
tree (its uncommitted changes included), each with its own numba cache. Every case of
:mod:`compare_cases` runs as a fresh process per tree, base and head alternating round by round
(so a machine slowing down mid-run hits both sides); the first round of each tree is a warm-up
that fills its numba cache and is not counted. Each cell is the median over the rounds.

Usage, from the project root with the venv active::

    python benchmarks/compare.py                      # HEAD~1 against the work tree
    python benchmarks/compare.py --base f577cad       # a named base
    python benchmarks/compare.py --base c717e64 --head 01e4ba4 --only capture,live
    python benchmarks/compare.py --quick              # smaller sizes, 2 rounds (~5 min)

The table prints ``head / base`` for every metric (lower is faster for times and for the
``/plain`` ratios; higher is faster for MPix/s) and marks a change worse than ``--threshold``
(default 1.2x) ``SLOWER``, better ``faster``. Exit 1 when anything got slower, so a script can
stop on it. Run it for every change to a kernel or a hot path (CONTRIBUTING.md), and quote the
table in the closing note.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
from compare_cases import CASES  # noqa: E402


def _git(*args: str, cwd: Path = ROOT) -> str:
    return subprocess.run(
        ["git", *args], cwd=cwd, check=True, capture_output=True, text=True
    ).stdout.strip()


def _tree(rev: str | None, tmp: Path, name: str) -> tuple[Path, str]:
    """``(folder, label)`` of a tree: a detached worktree of ``rev``, or the project itself."""
    if rev is None:
        dirty = " + changes" if _git("status", "--porcelain", "--untracked-files=no") else ""
        return ROOT, f"{_git('rev-parse', '--short', 'HEAD')}{dirty}"
    sha = _git("rev-parse", "--verify", f"{rev}^{{commit}}")
    path = tmp / name
    _git("worktree", "add", "--detach", "--force", str(path), sha)
    return path, _git("rev-parse", "--short", sha)


def _run_case(case: str, tree: Path, cache: Path, quick: bool, repeat: int) -> dict[str, float]:
    """One case in a fresh process importing ``sciviz_gbuf`` from ``tree``."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(tree), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    env["NUMBA_CACHE_DIR"] = str(cache)
    env.setdefault("PYVISTA_OFF_SCREEN", "true")
    if not env.get("DISPLAY"):  # headless: PyVista's plain Plotter straight to EGL, as ours
        env.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    cmd = [sys.executable, str(HERE / "compare_cases.py"), case, "--repeat", str(repeat)]
    if quick:
        cmd.append("--quick")
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=tree)
    if proc.returncode != 0:
        tail = (proc.stderr.strip().splitlines() or ["(no output)"])[-1]
        print(f"  {case} failed on {tree}: {tail}", file=sys.stderr)
        return {}
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _check_import(tree: Path, cache: Path) -> None:
    """The child really imports the tree's package (not the venv's editable install)."""
    env = dict(os.environ, PYTHONPATH=str(tree), NUMBA_CACHE_DIR=str(cache))
    where = subprocess.run(
        [sys.executable, "-c", "import sciviz_gbuf; print(sciviz_gbuf.__file__)"],
        env=env, capture_output=True, text=True, check=True, cwd=tree,
    ).stdout.strip()  # fmt: skip
    if not Path(where).resolve().is_relative_to(tree.resolve()):
        raise SystemExit(f"compare: {tree} imports sciviz_gbuf from {where}, not from the tree")


def _higher_is_better(metric: str) -> bool:
    return metric.endswith("/s")


def table(
    results: dict[str, dict[str, list[float]]], labels: tuple[str, str], threshold: float
) -> tuple[str, int]:
    """The markdown table and the number of metrics slower than ``threshold``."""
    rows = [
        f"| metric | base {labels[0]} | head {labels[1]} | head/base | |",
        "|---|---|---|---|---|",
    ]
    slower = 0
    metrics = list(dict.fromkeys([*results["base"], *results["head"]]))
    for metric in metrics:
        b = results["base"].get(metric)
        h = results["head"].get(metric)
        bm = statistics.median(b) if b else None
        hm = statistics.median(h) if h else None
        cell = lambda v: "-" if v is None else f"{v:.3g}"  # noqa: E731
        if bm and hm:
            ratio = hm / bm
            worse = 1.0 / ratio if _higher_is_better(metric) else ratio
            mark = "SLOWER" if worse > threshold else "faster" if worse < 1.0 / threshold else ""
            slower += mark == "SLOWER"
            rows.append(f"| {metric} | {cell(bm)} | {cell(hm)} | {ratio:.2f}x | {mark} |")
        else:
            rows.append(f"| {metric} | {cell(bm)} | {cell(hm)} | - | |")
    return "\n".join(rows), slower


def _toolchain() -> str:
    """The interpreter, compiler and CPU both trees ran on: a table is comparable with another
    run's only on the same (numba 0.68's LLVM alone made the sky view's march 4x slower on AMD
    Zen than the numba the table before it was measured with, and a base-against-head run
    cannot see that: both trees use the same compiler)."""
    from importlib import metadata

    parts = [f"Python {platform.python_version()}"]
    for dist in ("numba", "llvmlite", "numpy", "vtk"):
        try:
            parts.append(f"{dist} {metadata.version(dist)}")
        except metadata.PackageNotFoundError:
            parts.append(f"{dist} -")
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            names = (ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name"))
            cpu = next(names, cpu)
    except OSError:
        pass
    return ", ".join(parts) + f"; {cpu}, {os.cpu_count()} cores"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--base", default="HEAD~1", help="base commit (default: HEAD~1)")
    ap.add_argument("--head", default=None, help="head commit (default: the work tree)")
    ap.add_argument("--only", default=None, help=f"comma-separated cases of {sorted(CASES)}")
    ap.add_argument("--rounds", type=int, default=None, help="timed rounds (default 3, quick 2)")
    ap.add_argument("--repeat", type=int, default=3, help="timed runs within a case process")
    ap.add_argument("--threshold", type=float, default=1.2, help="ratio marked as a change")
    ap.add_argument("--quick", action="store_true", help="smaller sizes")
    ap.add_argument("--output", type=Path, default=None, help="also write the table here")
    args = ap.parse_args(argv)
    cases = list(CASES) if args.only is None else [c.strip() for c in args.only.split(",")]
    unknown = sorted(set(cases) - set(CASES))
    if unknown:
        print(f"compare: --only: unknown cases {unknown}; known: {sorted(CASES)}", file=sys.stderr)
        return 2
    rounds = args.rounds if args.rounds is not None else (2 if args.quick else 3)
    if not 1 <= rounds <= 20 or not 1 <= args.repeat <= 50:
        print("compare: --rounds must be 1-20 and --repeat 1-50", file=sys.stderr)
        return 2
    tmp = Path(tempfile.mkdtemp(prefix="sciviz_compare_"))
    trees: dict[str, tuple[Path, str]] = {}
    try:
        trees["base"] = _tree(args.base, tmp, "base")
        trees["head"] = _tree(args.head, tmp, "head")
        caches = {side: tmp / f"numba_{side}" for side in trees}
        for side, (path, _) in trees.items():
            _check_import(path, caches[side])
        labels = (trees["base"][1], trees["head"][1])
        print(f"# base {labels[0]} against head {labels[1]}: {rounds} rounds after a warm-up")
        print(f"# {_toolchain()}")
        results: dict[str, dict[str, list[float]]] = {"base": {}, "head": {}}
        for r in range(rounds + 1):
            order = ("base", "head") if r % 2 == 0 else ("head", "base")
            for case in cases:
                for side in order:
                    path, _ = trees[side]
                    got = _run_case(case, path, caches[side], args.quick, args.repeat)
                    if r == 0:
                        continue  # the warm-up round: numba caches filled, files touched
                    for metric, value in got.items():
                        results[side].setdefault(metric, []).append(float(value))
            print(f"  round {r}/{rounds} done" + (" (warm-up)" if r == 0 else ""), flush=True)
        text, slower = table(results, labels, args.threshold)
        print(text)
        if args.output is not None:
            args.output.write_text(f"<!-- {_toolchain()} -->\n" + text + "\n")
        return 1 if slower else 0
    finally:
        for side in ("base", "head"):
            if side in trees and trees[side][0] != ROOT:
                subprocess.run(
                    ["git", "worktree", "remove", "--force", str(trees[side][0])],
                    cwd=ROOT, capture_output=True,
                )  # fmt: skip
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    raise SystemExit(main())
