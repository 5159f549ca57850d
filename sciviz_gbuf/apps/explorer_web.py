"""The explorer's web page: a local trame app around :class:`~sciviz_gbuf.apps.explorer.Explorer`.

The picture travels as a JPEG data URL bound to an ``<img>`` (no remote VTK rendering): each
control change re-runs only the filters on the cached G-buffer and replaces the URL; camera
controls capture again. ``sciviz-gbuf explore`` serves it on 127.0.0.1 only.
"""

from __future__ import annotations

import time

from .explorer import RELIEF_VARIANTS, STYLES, VIEWS, encode_jpeg_data_url

__all__ = ["CAMERA", "MAP_SLIDERS", "PARAMS", "SLIDERS", "build_app"]

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


#: Parameters set by selects or ranged sliders rather than by :data:`SLIDERS`.
PARAMS = ("style", "contour_interval", "view", "relief", "map_interval")


def _dom_id(name: str) -> str:
    return "slider-" + name.replace("_", "-")


def build_app(explorer, *, port: int = 8080):
    """A trame server showing ``explorer``'s picture with a control per parameter.

    Returns
    -------
    trame_server.Server, not started (``server.start(host="127.0.0.1", ...)``).
    """
    from trame.app import get_server
    from trame.ui.vuetify3 import SinglePageLayout
    from trame.widgets import html
    from trame.widgets import vuetify3 as v3

    server = get_server(f"sciviz-gbuf-explore-{port}", client_type="vue3")
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

    def refresh() -> None:
        t0 = time.perf_counter()
        values = {name: state[name] for name, *_ in (*SLIDERS, *MAP_SLIDERS)}
        for name in PARAMS:
            values[name] = state[name]
        try:
            rgb = explorer.render_image(values)
        except Exception as exc:  # shown in the page; the last good picture stays
            state.error = str(exc)
            return
        state.error = ""
        state.image_url = encode_jpeg_data_url(rgb)
        # A map has one pixel per DEM cell: small DEMs are shown enlarged.
        state.image_style = (
            f"width: {max(rgb.shape[1], 768)}px; max-width: 100%"
            if values["view"] == "map"
            else "max-width: 100%"
        )
        state.filter_ms = round(explorer.last_ms, 1)
        state.update_ms = round((time.perf_counter() - t0) * 1e3, 1)

    @state.change(*PARAMS, *(name for name, *_ in (*SLIDERS, *MAP_SLIDERS)))
    def _on_params(**_) -> None:
        refresh()

    @state.change(*(name for name, *_ in CAMERA))
    def _on_camera(**_) -> None:
        try:
            explorer.set_camera(state.camera_azimuth, state.camera_elevation, state.camera_zoom)
        except Exception as exc:
            state.error = str(exc)
            return
        refresh()

    def slider(name: str, label: str, lo_: float, hi_, step) -> None:
        # The id sits on a wrapper: Vuetify hands a slider's own id to its label.
        with html.Div(id=_dom_id(name)):
            v3.VSlider(
                v_model=(name,),
                label=label,
                min=lo_,
                max=hi_,
                step=step,
                thumb_label=True,
                density="compact",
                hide_details=True,
                classes="my-1",
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
                with v3.VCol():
                    html.Img(src=("image_url",), id="image", style=("image_style",))
    refresh()
    return server
