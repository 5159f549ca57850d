"""The layout rules of CONTRIBUTING.md, checked on the package's own source.

Every import statement counts, at module level or inside a function, absolute or relative. The
checkers are plain functions of a source tree; each is also run on a small synthetic package
that breaks its rule, so a checker that stopped seeing violations would fail here too.
"""

from __future__ import annotations

import ast
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

import sciviz_gbuf
from sciviz_gbuf import filters, readers, styles
from sciviz_gbuf import vtk_algorithms as V
from sciviz_gbuf.cli import build_parser
from sciviz_gbuf.core.gbuffer import GBuffer

PACKAGE = Path(sciviz_gbuf.__file__).parent

#: Layers from the bottom; a module may import its own layer and the ones below (as in
#: pyproject.toml's import-linter contract, which `lint-imports` checks the same way).
LAYERS = (
    ("errors", "_validate", "_progress", "_dask", "_atomic"),
    ("readers",),
    ("datasets",),
    ("core", "isosurface"),
    ("filters",),
    ("styles",),
    ("writers",),
    ("compose",),
    ("recipes",),
    ("live",),
    ("pyvista_plugin", "vtk_algorithms"),
    ("apps",),
    ("cli",),
)
MAX_TOP_LEVEL_MODULES = 12


@dataclass(frozen=True)
class Import:
    importer: str  # dotted module name
    target: str  # dotted module imported (a package means its __init__)
    names: tuple[str, ...]  # names taken from it (empty for `import x`)
    line: int
    in_function: bool


def modules(root: Path) -> dict[str, Path]:
    """Dotted name -> file of every module of the package at ``root``."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def imports(root: Path) -> list[Import]:
    """Every import of a package module by a package module."""
    mods = modules(root)
    out = []
    for name, path in mods.items():
        is_pkg = path.name == "__init__.py"
        tree = ast.parse(path.read_text(encoding="utf-8"))
        top = {id(n) for n in tree.body}
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = name.split(".") if is_pkg else name.split(".")[:-1]
                    base = base[: len(base) - (node.level - 1)]
                    target = ".".join([*base, *([node.module] if node.module else [])])
                else:
                    target = node.module or ""
                if target != root.name and not target.startswith(root.name + "."):
                    continue
                plain = []
                for alias in node.names:
                    sub = f"{target}.{alias.name}"
                    if sub in mods:  # `from pkg import module`
                        out.append(Import(name, sub, (), node.lineno, id(node) not in top))
                    else:
                        plain.append(alias.name)
                if plain:
                    out.append(Import(name, target, tuple(plain), node.lineno, id(node) not in top))
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name == root.name or alias.name.startswith(root.name + "."):
                        out.append(Import(name, alias.name, (), node.lineno, id(node) not in top))
    return out


def cycles(root: Path) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan), plus self-imports."""
    graph: dict[str, set[str]] = {m: set() for m in modules(root)}
    for imp in imports(root):
        if imp.target in graph:
            graph[imp.importer].add(imp.target)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10_000))

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in graph[v]:
                found.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    return found


def _private(part: str) -> bool:
    return part.startswith("_") and not (part.startswith("__") and part.endswith("__"))


def private_uses(root: Path) -> list[str]:
    """Private names taken from another module, and private modules used outside their
    parent package."""
    bad = []
    for imp in imports(root):
        where = f"{imp.importer}:{imp.line}"
        if imp.target != imp.importer:
            bad += [f"{where} takes {imp.target}.{n}" for n in imp.names if _private(n)]
        parts = imp.target.split(".")
        for i, part in enumerate(parts):
            if _private(part):
                parent = ".".join(parts[:i])
                if not (imp.importer == parent or imp.importer.startswith(parent + ".")):
                    bad.append(f"{where} uses private module {imp.target}")
                break
    return bad


def layer_of(module: str, root_name: str) -> int | None:
    parts = module.split(".")
    if len(parts) < 2:
        return None  # the package's own __init__ re-exports every layer
    for i, layer in enumerate(LAYERS):
        if parts[1] in layer:
            return i
    return None


def back_edges(root: Path) -> list[str]:
    """Imports of a higher layer by a lower one."""
    bad = []
    for imp in imports(root):
        a, b = layer_of(imp.importer, root.name), layer_of(imp.target, root.name)
        if a is not None and b is not None and b > a:
            bad.append(f"{imp.importer}:{imp.line} imports {imp.target} (a higher layer)")
    return bad


def numba_outside_kernels(root: Path) -> list[str]:
    bad = []
    for name, path in modules(root).items():
        if path.stem.startswith("_") and path.stem.endswith("_kernels"):
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            mods = []
            if isinstance(node, ast.Import):
                mods = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and not node.level:
                mods = [node.module or ""]
            if any(m == "numba" or m.startswith("numba.") for m in mods):
                bad.append(f"{name}:{node.lineno}")
    return bad


def top_level_modules(root: Path) -> list[str]:
    return sorted(p.name for p in root.glob("*.py"))


# ------------------------------------------------------------------- the package itself
def test_no_import_cycles():
    assert cycles(PACKAGE) == []


def test_only_public_names_cross_module_boundaries():
    assert private_uses(PACKAGE) == []


def test_layers_run_one_way():
    assert back_edges(PACKAGE) == []
    listed = {m for layer in LAYERS for m in layer}
    children = {p.stem for p in PACKAGE.glob("*.py")} | {
        p.name for p in PACKAGE.iterdir() if (p / "__init__.py").is_file()
    }
    assert children - listed == {"__init__", "__main__"}  # every module has its layer


def test_numba_only_in_kernel_modules():
    assert numba_outside_kernels(PACKAGE) == []


def test_few_top_level_modules():
    assert len(top_level_modules(PACKAGE)) <= MAX_TOP_LEVEL_MODULES, top_level_modules(PACKAGE)


def test_import_linter_contracts_kept():
    exe = shutil.which("lint-imports", path=str(Path(sys.executable).parent))
    if exe is None:
        pytest.skip("import-linter is not installed")
    root = PACKAGE.parent
    run = subprocess.run(
        [exe, "--config", str(root / "pyproject.toml")],
        cwd=root,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-2000:]
    assert "3 kept, 0 broken" in run.stdout


# ------------------------------------------------------------------- the checkers can fail
def _synthetic(tmp_path: Path, files: dict[str, str]) -> Path:
    root = tmp_path / "pkg"
    for rel, text in files.items():
        f = root / rel
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(text)
    return root


def test_checkers_find_each_kind_of_violation(tmp_path):
    root = _synthetic(
        tmp_path,
        {
            "__init__.py": "",
            "errors.py": "def f():\n    from .filters import g\n",  # function-level back edge
            "filters/__init__.py": "from .a import g\n",
            "filters/a.py": (
                "from . import _k_kernels\nimport numba\n\ndef g():\n    from . import b\n"
            ),
            "filters/b.py": "from .a import g\n",  # a <-> b only through a function import
            "filters/_k_kernels.py": "import numba\n",
            "core/__init__.py": "from ..filters._k_kernels import x\nfrom ..filters.a import _y\n",
        },
    )
    assert cycles(root) == [["pkg.filters.a", "pkg.filters.b"]]
    bad = private_uses(root)
    assert any("takes pkg.filters.a._y" in b for b in bad)
    assert any("uses private module pkg.filters._k_kernels" in b for b in bad)
    assert not any(b.startswith("pkg.filters.a:") for b in bad)  # its own package may use it
    assert sorted(back_edges(root)) == [
        "pkg.core:1 imports pkg.filters._k_kernels (a higher layer)",  # core sits below filters
        "pkg.core:2 imports pkg.filters.a (a higher layer)",
        "pkg.errors:2 imports pkg.filters (a higher layer)",
    ]
    assert numba_outside_kernels(root) == ["pkg.filters.a:2"]


# ------------------------------------------------------------------- the registries
def _tiny_gbuffer() -> GBuffer:
    import pyvista as pv

    return sciviz_gbuf.capture(pv.Sphere(), window_size=(40, 30))


def test_style_registry_serves_every_front_end():
    gb = _tiny_gbuffer()
    assert set(styles.FRONTS) == {f for s in styles.STYLES.values() for f in s.fronts}
    for name, style in styles.STYLES.items():
        assert style.name == name
        if style.draw is None:
            assert style.fronts == {"live"}, name  # only the overlay draws its own
            continue
        img = style.draw(gb)
        assert img.shape[:2] == gb.output_shape and img.shape[2] in (3, 4), name
        assert np.nanmin(img) >= 0 and np.nanmax(img) <= 1, name
    # every front end offers exactly the registry's styles for it (aliases besides)
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices
    edges = next(a for a in sub["edges"]._actions if a.dest == "style")
    mesh = next(a for a in sub["mesh"]._actions if a.dest == "style")
    assert set(edges.choices) == set(styles.styles_for("illustrate"))
    npr = styles.styles_for("npr")
    aliases = {a for s in styles.STYLES.values() if "npr" in s.fronts for a in s.aliases}
    assert set(mesh.choices) == set(npr) | aliases
    from sciviz_gbuf.apps.explorer import STYLES as EXPLORER_STYLES
    from sciviz_gbuf.live import LIVE_STYLES
    from sciviz_gbuf.styles.fused import FUSED_MODES

    assert LIVE_STYLES == styles.styles_for("live")
    assert EXPLORER_STYLES == styles.styles_for("explore") and set(FUSED_MODES) == set(
        EXPLORER_STYLES
    )


def test_style_registry_refuses_clashes():
    with pytest.raises(ValueError, match="already registered"):
        styles.register("gooch", "again", fronts=("npr",))
    with pytest.raises(ValueError, match="fronts"):
        styles.register("new-style", "nowhere", fronts=("nowhere",))
    assert styles.check_style("lines", "npr") == "drawing"  # the old name, npr only
    assert styles.check_style("lines", "illustrate") == "lines"


def test_filter_registry_generates_the_vtk_algorithms():
    assert set(V.ALGORITHMS) == {"capture", *filters.registry.FILTERS}
    for name, f in filters.registry.FILTERS.items():
        assert getattr(filters, name) is f.func, name  # a public filter
        cls = V.ALGORITHMS[name]
        assert getattr(V, cls.__name__) is cls and cls.__name__ in V.__all__
        assert cls.__name__ in V.__doc__  # the generated class table
        assert (name in V.ARRAY_FILTERS) == (f.takes == "array")


def test_reader_suffix_table_is_the_only_one(tmp_path):
    dem_suffixes = readers.suffixes("dem")
    from sciviz_gbuf.apps.explorer import DEM_SUFFIXES

    assert DEM_SUFFIXES == dem_suffixes
    z = np.arange(12, dtype=np.float32).reshape(3, 4)
    for suffix in dem_suffixes:
        assert readers.kind_of(tmp_path / f"x{suffix}") == "dem"
    assert readers.kind_of(tmp_path / "x.bpt") == "patches"
    assert readers.kind_of(tmp_path / "x.stl") == "mesh"
    assert readers.kind_of(tmp_path) == "dicom"
    np.save(tmp_path / "z.npy", z)
    data, kind = readers.read_scene(tmp_path / "z.npy")
    assert kind == "dem" and np.array_equal(data.heights, z)
    unknown = tmp_path / "z.xyz"
    unknown.write_text("1 2 3\n")
    with pytest.raises(sciviz_gbuf.InputError, match="unknown DEM extension"):
        readers.read_dem(unknown)
