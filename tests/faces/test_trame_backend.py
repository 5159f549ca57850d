"""The live edge overlay through PyVista's trame Jupyter backends, seen in a real browser.

``pl.show(jupyter_backend=...)`` on a notebook plotter is exactly what a Jupyter cell runs:
PyVista hands the plotter to trame-pyvista's ``show_trame``, which builds PyVista's own UI
(``Viewer.ui``: ``PyVistaRemoteView`` for ``'server'``, ``PyVistaRemoteLocalView`` for
``'trame'``, ``PyVistaLocalView`` for ``'client'``) on a trame server and returns the iframe URL.
Here the trame server runs in this process's event loop (as in the kernel), on 127.0.0.1 and a
free port; headless Chromium (selenium, in a worker thread) loads the URL, and the view's pixels
are compared with the edge map of an independent capture (:func:`sciviz_gbuf.capture` +
:func:`~sciviz_gbuf.filters.edge_map`) for the camera the server has at that moment. The frames
are JPEG-compressed and rescaled by the browser, so we compare the positions of red profile
pixels with a one-pixel tolerance.
"""

from __future__ import annotations

import asyncio
import io
import itertools
import os
import shutil
import time
import warnings

import numpy as np
import pytest
import pyvista as pv
from pyvista import examples
from scipy import ndimage

import sciviz_gbuf as sg
from sciviz_gbuf import live as _live
from sciviz_gbuf.filters import edge_map

trame_pyvista = pytest.importorskip("trame_pyvista", reason="needs trame-pyvista (PyVista>=0.49)")
pytest.importorskip("selenium", reason="needs selenium")
Image = pytest.importorskip("PIL.Image", reason="needs pillow")

from selenium import webdriver  # noqa: E402
from selenium.webdriver.chrome.options import Options  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from trame_pyvista.jupyter import launch_server  # noqa: E402

CHROMIUM = next(
    filter(None, map(shutil.which, ("chromium", "chromium-browser", "google-chrome"))), None
)
CHROMEDRIVER = shutil.which("chromedriver")
pytestmark = pytest.mark.skipif(
    CHROMIUM is None or CHROMEDRIVER is None,
    reason="needs headless Chromium and chromedriver (apt-get install chromium chromium-driver)",
)

RED, BLUE = (1.0, 0.0, 0.0), (0.0, 0.0, 1.0)
_names = itertools.count()

# The largest visible on-screen <canvas>/<img> (the view's frame; an element screenshot is a
# crop of the page, so any of the view's stacked layers gives what the user sees), and the
# rectangles of PyVista's menu card floating over it, relative to that element.
_FIND_VIEW = """
const els = [...document.querySelectorAll('canvas, img')].filter(e => {
  const r = e.getBoundingClientRect(), s = getComputedStyle(e);
  return r.width > 50 && r.height > 50 && s.display !== 'none' && s.visibility !== 'hidden'
         && e.offsetParent !== null && r.left >= 0 && r.top >= 0  // vtk.js parks spares at -20000
         && r.right <= innerWidth + 1 && r.bottom <= innerHeight + 1;
});
if (!els.length) return null;
els.sort((a, b) => b.clientWidth * b.clientHeight - a.clientWidth * a.clientHeight);
const v = els[0], r = v.getBoundingClientRect();
const menus = [...document.querySelectorAll('.v-card')].map(m => {
  const q = m.getBoundingClientRect();
  return [q.left - r.left, q.top - r.top, q.right - r.left, q.bottom - r.top];
});
return [v, menus];
"""


@pytest.fixture(scope="module")
def browser():
    opts = Options()
    opts.binary_location = CHROMIUM
    for arg in (
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-dev-shm-usage",
        "--window-size=520,420",
        "--force-device-scale-factor=1",
        "--hide-scrollbars",
    ):
        opts.add_argument(arg)
    try:
        driver = webdriver.Chrome(options=opts, service=Service(CHROMEDRIVER))
    except Exception as exc:  # e.g. a Chromium/driver version mismatch
        pytest.skip(f"cannot start headless Chromium: {exc}")
    driver.set_page_load_timeout(60)
    yield driver
    driver.quit()


@pytest.fixture(autouse=True)
def _offline_trame(monkeypatch):
    """Keep trame-vtklocal (loaded by launch_server for the 'wasm' mode) from downloading."""
    try:
        from trame_vtklocal.module import wasm
    except ImportError:
        return

    async def _no_download(*_args, **_kwargs):
        return None

    monkeypatch.setattr(wasm, "setup_wasm_directory", _no_download)


@pytest.fixture(scope="module")
def nut() -> pv.PolyData:
    return examples.load_nut()


def _plotter(nut: pv.PolyData, *, enhance: bool = True) -> pv.Plotter:
    pl = pv.Plotter(notebook=True, window_size=(400, 300))
    pl.background_color = "white"
    pl.add_mesh(nut, color="lightgray")
    if enhance:
        pl.gbuf.enable_edge_enhancement(profile_color=RED, inner_color=BLUE)
    return pl


# ---------------------------------------------------------------------- image comparison
def _red(img: np.ndarray) -> np.ndarray:
    rgb = img[..., :3].astype(np.int16)
    return (rgb[..., 0] >= 150) & (rgb[..., 0] - rgb[..., 1:].max(axis=-1) >= 60)


def _blue(img: np.ndarray) -> np.ndarray:
    rgb = img[..., :3].astype(np.int16)
    return (rgb[..., 2] >= 150) & (rgb[..., 2] - rgb[..., :2].max(axis=-1) >= 60)


def _expected(pl: pv.Plotter) -> np.ndarray:
    """Edge map of an independent capture of the plotter, at its current camera and size."""
    return edge_map(sg.capture(pl), operator="diagonal", crease_angle=30.0)


def _agreement(img: np.ndarray, emap: np.ndarray, keep: np.ndarray) -> dict[str, float]:
    """Recall (strong profile pixels with a red pixel within 1 px), precision, and the same
    recall for the inner edges (blue); pixels under the menu card (``~keep``) are ignored."""
    ring = np.ones((3, 3), bool)
    red, blue = _red(img) & keep, _blue(img) & keep
    prof = (emap[..., 3] >= 0.9) & keep
    inner = (emap[..., 0] >= 0.9) & (emap[..., 3] <= 0.1) & keep
    ink = ndimage.binary_dilation(emap[..., 3] > 0.05, ring)
    return {
        "recall": float((prof & ndimage.binary_dilation(red, ring)).sum() / max(prof.sum(), 1)),
        "precision": float((red & ink).sum() / max(red.sum(), 1)),
        "inner_recall": float(
            (inner & ndimage.binary_dilation(blue, ring)).sum() / max(inner.sum(), 1)
        ),
        "n_prof": int(prof.sum()),
        "n_red": int(red.sum()),
    }


# ---------------------------------------------------------------------- browser side
class _Page:
    """The browser, driven from a worker thread so the trame server keeps serving meanwhile."""

    def __init__(self, driver) -> None:
        self.driver = driver

    async def call(self, fn, *args):
        return await asyncio.get_running_loop().run_in_executor(None, fn, *args)

    def _grab(self) -> tuple[np.ndarray, np.ndarray] | None:
        found = self.driver.execute_script(_FIND_VIEW)
        if not found:
            return None
        element, menus = found
        img = np.asarray(Image.open(io.BytesIO(element.screenshot_as_png)).convert("RGB"))
        keep = np.ones(img.shape[:2], bool)
        for x0, y0, x1, y1 in menus:  # the floating menu card (and its shadow) hides the view
            r0, r1 = max(int(y0) - 8, 0), max(int(y1) + 8, 0)
            keep[r0:r1, max(int(x0) - 8, 0) : max(int(x1) + 8, 0)] = False
        return img, keep

    async def frame(
        self, accept=lambda img: True, timeout: float = 30.0
    ) -> tuple[np.ndarray, np.ndarray]:
        """The view's image once ``accept`` holds and two grabs in a row are identical."""
        last = None
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            got = await self.call(self._grab)
            if got is not None:
                img, keep = got
                nonblank = (np.abs(img.astype(np.int16) - 255).sum(axis=-1) > 60).mean() > 0.05
                if nonblank and accept(img):
                    if last is not None and last.shape == img.shape and np.array_equal(last, img):
                        return img, keep
                    last = img
                else:
                    last = None
            await asyncio.sleep(0.1)
        raise AssertionError("the browser view never showed a settled frame")

    async def drag(self, dx: int, dy: int) -> None:
        def _drag() -> None:
            element = self.driver.execute_script(_FIND_VIEW)[0]
            chain = ActionChains(self.driver).move_to_element(element).click_and_hold()
            for _ in range(6):
                chain = chain.move_by_offset(dx // 6, dy // 6).pause(0.03)
            chain.release().perform()

        await self.call(_drag)


async def _start(mode: str, pl: pv.Plotter, driver) -> tuple[object, object, _Page]:
    """Launch a trame server as the Jupyter backend does, show ``pl`` and load the iframe URL."""
    name = f"sciviz-gbuf-test-{next(_names)}"
    server = launch_server(name, port=0, host="127.0.0.1")
    await server.ready
    shown = {}

    def handler(viewer, src, **_kwargs):  # jupyter_kwargs["handler"]: instead of the iframe
        shown.update(viewer=viewer, src=src)
        return src

    # exactly what a notebook cell `pl.show(jupyter_backend=mode)` runs (PyVista -> show_trame)
    src = pl.show(
        jupyter_backend=mode,
        return_viewer=True,
        jupyter_kwargs={"name": name, "handler": handler, "host": "127.0.0.1"},
    )
    assert src == shown["src"] and f":{server.port}/index.html?ui=" in src
    page = _Page(driver)
    await page.call(driver.get, src)
    return server, shown["viewer"], page


def _run(coro):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        return asyncio.run(coro)


# ---------------------------------------------------------------------- tests
def test_server_backend_streams_the_overlay(browser, nut):
    """jupyter_backend='server': the streamed frames carry the overlay, for every camera."""
    pl = _plotter(nut)
    stats = {}

    async def scenario() -> None:
        t0 = time.perf_counter()
        server, _viewer, page = await _start("server", pl, browser)
        try:
            img, keep = await page.frame(lambda im: _red(im).sum() > 200)
            stats["first_frame_s"] = time.perf_counter() - t0
            # the browser shows the server's window pixel for pixel (no browser-side scaling)
            assert img.shape[:2] == tuple(pl.window_size)[::-1]
            first = _expected(pl)
            stats["first"] = a = _agreement(img, first, keep)
            assert a["n_prof"] > 300, a
            assert a["recall"] >= 0.9 and a["precision"] >= 0.9, a
            assert a["inner_recall"] >= 0.8, a
            assert _live.client_side_views(pl) == []

            # camera moved from Python (a later notebook cell): pl.render() pushes a new frame
            updates = pl.gbuf.live.updates
            pl.camera.azimuth += 30
            t1 = time.perf_counter()
            pl.render()
            img2, keep2 = await page.frame(lambda im: not np.array_equal(im, img))
            stats["camera_update_s"] = time.perf_counter() - t1
            assert pl.gbuf.live.updates > updates
            stats["moved"] = b = _agreement(img2, _expected(pl), keep2)
            assert b["recall"] >= 0.9 and b["precision"] >= 0.9, b
            stale = _agreement(img2, first, keep2)  # the old edges are gone
            assert stale["recall"] < 0.5, stale

            # camera moved in the browser: trame forwards the drag to the server's interactor
            cam = pl.camera_position
            t2 = time.perf_counter()
            await page.drag(80, 20)
            img3, keep3 = await page.frame(lambda im: not np.array_equal(im, img2))
            stats["drag_update_s"] = time.perf_counter() - t2
            assert pl.camera_position != cam
            stats["dragged"] = c = _agreement(img3, _expected(pl), keep3)
            assert c["recall"] >= 0.9 and c["precision"] >= 0.9, c

            # removable: the next frame has no overlay
            t3 = time.perf_counter()
            pl.gbuf.disable_edge_enhancement()
            img4, keep4 = await page.frame(lambda im: _red(im).sum() == 0)
            stats["disable_update_s"] = time.perf_counter() - t3
            d = _agreement(img4, _expected(pl), keep4)
            assert d["n_red"] == 0 and d["recall"] == 0.0, d
            assert (np.abs(img4.astype(int) - 255).sum(axis=-1) > 60).mean() > 0.1  # mesh shown
        finally:
            await server.stop()

    _run(scenario())
    pl.close()
    print(stats)


def test_trame_backend_default_is_server_rendered_until_toggled(browser, nut):
    """jupyter_backend='trame' (PyVista's default): server rendering at start shows the
    overlay; switching its toggle to client-side (vtk.js) rendering loses it."""
    pl = _plotter(nut)

    async def scenario() -> None:
        server, viewer, page = await _start("trame", pl, browser)
        try:
            img, keep = await page.frame(lambda im: _red(im).sum() > 200)
            a = _agreement(img, _expected(pl), keep)
            assert a["recall"] >= 0.9 and a["precision"] >= 0.9, a
            assert _live.client_side_views(pl) == []
            # the menu's rendering-mode toggle, as a click would set it
            server.state[viewer.SERVER_RENDERING] = False
            server.state.flush()
            img2, _keep2 = await page.frame(lambda im: _red(im).sum() == 0)
            assert (np.abs(img2.astype(int) - 255).sum(axis=-1) > 60).mean() > 0.1
            assert _live.client_side_views(pl) == ["PyVistaRemoteLocalView"]
        finally:
            await server.stop()

    _run(scenario())
    pl.close()


def test_client_backend_warns_and_shows_the_plain_scene(browser, nut):
    """jupyter_backend='client': vtk.js re-renders the geometry; no overlay, and a warning."""
    pl = _plotter(nut)

    async def scenario() -> None:
        with pytest.warns(UserWarning, match="client-side trame view"):
            server, _viewer, page = await _start("client", pl, browser)
        try:
            assert _live.client_side_views(pl) == ["PyVistaLocalView"]
            img, _keep = await page.frame()
            assert _red(img).sum() == 0
        finally:
            await server.stop()

    _run(scenario())
    pl.close()


# ---------------------------------------------------------------------- a real Jupyter kernel
_KERNEL_SETUP = """
import numpy as np, pyvista as pv
import sciviz_gbuf as sg
from sciviz_gbuf.filters import edge_map
try:  # offline: keep trame-vtklocal (the 'wasm' mode) from downloading VTK-wasm
    from trame_vtklocal.module import wasm
    async def _no_download(*args, **kwargs):
        return None
    wasm.setup_wasm_directory = _no_download
except ImportError:
    pass
pv.set_jupyter_backend("server")
pl = pv.Plotter(window_size=(400, 300))
pl.background_color = "white"
pl.add_mesh(pv.examples.load_nut(), color="lightgray")
pl.gbuf.enable_edge_enhancement(profile_color=(1, 0, 0), inner_color=(0, 0, 1))
print("notebook", pl.notebook)
"""
_KERNEL_EXPECTED = "np.save({path!r}, edge_map(sg.capture(pl)))"


def test_jupyter_kernel_pl_show(browser, tmp_path, monkeypatch):
    """A real ipykernel runs `pl.show()` with the 'server' backend; the browser loads the
    iframe URL of the widget it displays; later cells move the camera and disable the overlay."""
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    pytest.importorskip("ipywidgets", reason="PyVista's trame widget needs ipywidgets")
    import re
    import sys
    from pathlib import Path

    monkeypatch.setenv("PATH", str(Path(sys.executable).parent) + ":" + os.environ["PATH"])
    expected = tmp_path / "emap.npy"
    sources = [
        _KERNEL_SETUP,
        "pl.show()",  # exactly what a user types
        _KERNEL_EXPECTED.format(path=str(expected)),
        "pl.camera.azimuth += 30\npl.render()",
        "pl.gbuf.disable_edge_enhancement()",
    ]
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(s) for s in sources])
    client = nbclient.NotebookClient(
        nb, timeout=60, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    )
    page = _Page(browser)

    def frame(accept):
        return asyncio.run(page.frame(accept))

    def run(index: int) -> str:
        cell = nb.cells[index]
        client.execute_cell(cell, index)
        errors = [o for o in cell.outputs if o.output_type == "error"]
        assert not errors, errors[0]["traceback"]
        return "".join(
            o.get("text", "") + o.get("data", {}).get("text/plain", "") for o in cell.outputs
        )

    with client.setup_kernel():
        assert "notebook True" in run(0)
        shown = run(1)  # the widget's repr: HTML(value='<iframe src="http://...
        src = re.search(r'src="(http://[^"]+)"', shown)
        assert src, shown
        browser.get(src.group(1).replace("&amp;", "&"))
        img, keep = frame(lambda im: _red(im).sum() > 200)
        run(2)
        a = _agreement(img, np.load(expected), keep)
        assert a["recall"] >= 0.9 and a["precision"] >= 0.9, a
        first = np.load(expected)
        run(3)
        img2, keep2 = frame(lambda im: not np.array_equal(im, img))
        run(2)
        b = _agreement(img2, np.load(expected), keep2)
        assert b["recall"] >= 0.9 and b["precision"] >= 0.9, b
        assert _agreement(img2, first, keep2)["recall"] < 0.5
        run(4)
        img3, _ = frame(lambda im: _red(im).sum() == 0)
        assert (np.abs(img3.astype(int) - 255).sum(axis=-1) > 60).mean() > 0.1
    print({"kernel_first": a, "kernel_moved": b})
