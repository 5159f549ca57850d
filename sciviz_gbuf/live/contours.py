"""Live contour lines on the GPU: Saito & Takahashi's image-space contour lines (1990
Eq. 7-15) drawn by an actor's own shaders, in the one pass that draws the actor.

The lines are those of :func:`sciviz_gbuf.filters.contour_lines` with regular levels: the
same line profile, major family and flat (Eq. 11) and dense-line (Eq. 15) fades, from the same
parameters (:func:`sciviz_gbuf.filters.contour_line_parameters`). The field is a point array
of the actor's data (mapped to a vertex attribute) or the world height along an axis
(unprojected from the vertex's clip position with the camera's inverse, so VTK's coordinate
shift for far-from-origin data, a UTM DEM, does not enter); Eq. 9's gradient is the field's
screen-space derivative. Every parameter is a custom uniform of the actor's shader property:
changing a value compiles nothing (the program holds the parts of Eq. 7-15 in use, see
:func:`.glsl.contour_fs_impl`: turning one on or off swaps to that program, compiled once),
and disabling removes exactly what was added.

The CPU route's lines (``capture`` the field as a G-buffer scalar, ``contour_lines`` of it)
are the reference: the two agree to within a pixel (tested). What the shader cannot do is look
at the neighbouring pixels, so a level the surface comes within half a line width of without
crossing (a summit just below it) draws a small mark the CPU route omits, and the
generalisation (smoothing, ring removal) of the printed maps is not applied.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from vtkmodules.vtkCommonDataModel import vtkDataObject
from vtkmodules.vtkRenderingCore import vtkDataSetMapper, vtkPolyDataMapper

from .. import _validate
from ..errors import InputError
from ..filters.contours import contour_line_parameters
from . import glsl

__all__ = ["AXES", "ContourField", "LiveContours", "contour_options", "shader_features"]

#: World axes a height field can follow (``height="z"``, or any 3-vector).
AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}

#: The shader's uniform of each parameter of :func:`~sciviz_gbuf.filters.contour_line_parameters`.
_UNIFORMS = {
    "base": "sgBase",
    "q": "sgQ",
    "line_a": "sgLineA",
    "line_cap": "sgLineCap",
    "line_b": "sgLineB",
    "p1": "sgP1",
    "p2": "sgP2",
    "p3": "sgP3",
    "inv_geps": "sgInvGeps",
    "c_sparse": "sgCSparse",
    "c_dense": "sgCDense",
    "dense_at": "sgDenseAt",
    "inv_d": "sgInvD",
    "major_q": "sgMajorQ",
    "major_a": "sgMajorA",
    "major_cap": "sgMajorCap",
}
_ATTRIBUTE = "sgContourScalar"


class ContourField:
    """What the lines follow: a point array ``scalars`` of the actor's data, or the world
    height along ``axis`` (a unit 3-vector)."""

    def __init__(self, scalars: str | None, axis: tuple[float, float, float] | None) -> None:
        self.scalars = scalars
        self.axis = axis

    @classmethod
    def checked(cls, actor: Any, scalars: object, height: object) -> ContourField:
        """The field of ``actor`` from the arguments of ``enable_contour_lines``."""
        if scalars is not None and height is not None:
            raise InputError("contour lines: give scalars= or height=, not both")
        if scalars is None:
            return cls(None, _axis(height if height is not None else "z"))
        if not isinstance(scalars, str) or not scalars:
            raise InputError(f"scalars: expected the name of a point array, got {scalars!r}")
        data = actor.GetMapper().GetInput()
        arr = None if data is None else data.GetPointData().GetArray(scalars)
        if arr is None:
            names = [] if data is None else _point_arrays(data)
            raise InputError(
                f"scalars: the actor's data has no point array {scalars!r} "
                f"(point arrays: {', '.join(names) or 'none'})"
            )
        if arr.GetNumberOfComponents() != 1:
            raise InputError(
                f"scalars: expected a point array with one component, {scalars!r} has "
                f"{arr.GetNumberOfComponents()}"
            )
        return cls(scalars, None)


def _point_arrays(data: Any) -> list[str]:
    pd = data.GetPointData()
    return [pd.GetArrayName(k) for k in range(pd.GetNumberOfArrays()) if pd.GetArrayName(k)]


def _axis(value: object) -> tuple[float, float, float]:
    if isinstance(value, str):
        if value not in AXES:
            raise InputError(f"height: expected one of 'x', 'y', 'z' or a 3-vector, got {value!r}")
        return AXES[value]
    try:
        v = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        v = np.zeros(0)
    if v.size != 3 or not np.all(np.isfinite(v)) or not np.linalg.norm(v) > 0:
        raise InputError(
            f"height: expected one of 'x', 'y', 'z' or a nonzero 3-vector, got {value!r}"
        )
    v = v / np.linalg.norm(v)
    return float(v[0]), float(v[1]), float(v[2])


def contour_options(
    *,
    interval: float,
    major_interval: float | None,
    base: float,
    width: float,
    major_width: float | None,
    profile: str,
    c_dense: float | None,
    dense_spacing: float | None,
    g_eps: float | None,
    c_sparse: float,
    color: Sequence[float],
    opacity: float,
) -> dict[str, Any]:
    """The checked uniforms of the lines (every value, before the shaders are touched)."""
    values = contour_line_parameters(
        interval=interval, base=base, width=width, profile=profile, g_eps=g_eps,
        c_sparse=c_sparse, c_dense=c_dense, dense_spacing=dense_spacing,
        major_interval=major_interval, major_width=major_width,
    )  # fmt: skip
    _validate.rgb(color, "color")
    rgb = [float(v) for v in np.asarray(color, dtype=np.float64).reshape(-1)]
    floats = {_UNIFORMS[k]: v for k, v in values.items()}
    # reciprocals taken once (the CPU kernel's loop-invariant 1 / q, in float32 as it is)
    floats["sgInvQ"] = float(np.float32(1.0) / np.float32(values["q"]))
    mq = np.float32(values["major_q"])
    floats["sgInvMajorQ"] = float(np.float32(1.0) / mq) if mq > 0 else 0.0
    # products of uniforms the shader would otherwise form per fragment (glsl.contour_fs_impl)
    f32 = np.float32
    floats["sgQB"] = float(f32(values["q"]) * f32(values["line_b"]))
    floats["sgMajorQB"] = float(mq * f32(values["line_b"]))
    floats["sgDenseK1"] = float(f32(values["q"]) * f32(values["inv_d"]))
    floats["sgDenseK0"] = float(f32(1.0) - f32(values["dense_at"]) * f32(values["inv_d"]))
    return {
        "floats": floats,
        "color": rgb,
        "opacity": _validate.number_in(opacity, "opacity", 0.0, 1.0),
        "features": shader_features(values),
    }


def shader_features(values: dict[str, float]) -> frozenset[str]:
    """The parts of the fragment shader (:func:`.glsl.contour_fs_impl`) that the parameters
    of :func:`~sciviz_gbuf.filters.contour_line_parameters` use."""
    f = set()
    if values["major_q"] > 0:
        f.add("major")
    if (values["p1"], values["p2"], values["p3"]) != (1.0, 0.0, 0.0):
        f.add("poly")
    if values["line_cap"] != 1.0 or (values["major_q"] > 0 and values["major_cap"] != 1.0):
        f.add("cap")
    if values["c_sparse"] > 0:
        f.add("sparse")
    if values["dense_at"] > -1e29:
        f.add("dense")
        if values["c_dense"] > 0:
            f.add("cdense")
    if "dense" not in f:
        # Eq. 13-14's second term, the level beyond the nearest, adds ink only where two lines
        # are closer than their widths: with dense fading the minors have faded there (at
        # dense_at, twice the width by default) and the majors merge into solid ink either
        # way, so the shader leaves it out (12 operations a fragment)
        f.add("beyond")
    return frozenset(f)


def _renderer_of(plotter: Any, actor: Any) -> Any:
    for ren in plotter.renderers:
        if ren.HasViewProp(actor):
            return ren
    raise InputError("actor: not in any of the plotter's subplots (add it with add_mesh first)")


class LiveContours:
    """Contour lines drawn by the shaders of one actor of a plotter.

    Parameters
    ----------
    plotter : pyvista.BasePlotter
    actor : vtkActor
        A surface actor (``pl.add_mesh`` returns one); its mapper a ``vtkDataSetMapper``
        (PyVista's) or a ``vtkPolyDataMapper``.
    field : ContourField
    options : dict
        :func:`contour_options`.
    """

    def __init__(self, plotter: Any, actor: Any, field: ContourField, options: dict) -> None:
        mapper = actor.GetMapper() if hasattr(actor, "GetMapper") else None
        if not isinstance(mapper, (vtkDataSetMapper, vtkPolyDataMapper)):
            kind = type(mapper).__name__ if mapper is not None else type(actor).__name__
            raise InputError(
                f"actor: expected a surface actor drawn by a vtkDataSetMapper or "
                f"vtkPolyDataMapper, got {kind}"
            )
        self._plotter = plotter
        self._actor = actor
        self._mapper = mapper
        self._renderer = _renderer_of(plotter, actor)
        self.field = field
        self.options = options
        self._observer: int | None = None
        self._attached = False
        self._mapped: Any = None  # the polydata mapper holding our attribute mapping

    # ------------------------------------------------------------------ lifecycle
    def attach(self) -> None:
        """Add the shader replacements, uniforms and the per-frame observer."""
        sp = self._actor.GetShaderProperty()
        scalar = self.field.scalars is not None
        vs_dec = glsl.CONTOUR_VS_DEC_SCALAR if scalar else glsl.CONTOUR_VS_DEC_HEIGHT
        vs_impl = glsl.CONTOUR_VS_IMPL_SCALAR if scalar else glsl.CONTOUR_VS_IMPL_HEIGHT
        sp.AddVertexShaderReplacement("//VTK::Normal::Dec", True, vs_dec, False)
        sp.AddVertexShaderReplacement("//VTK::Normal::Impl", True, vs_impl, False)
        sp.AddFragmentShaderReplacement("//VTK::Normal::Dec", True, glsl.CONTOUR_FS_DEC, False)
        self._set_program(self.options["features"])
        self._set_uniforms()
        if not scalar:
            self._set_height_plane()
        self._map_attribute()
        # before the subplot draws: the height's camera terms, the attribute's mapping
        self._observer = self._renderer.AddObserver("StartEvent", self._on_start)
        self._attached = True

    def set_options(self, options: dict) -> None:
        """New line parameters: uniforms only, unless they turn a part of the shader on or off
        (majors, a non-linear profile, c_sparse/c_dense > 0, dense-line fading): then that
        program, compiled once and kept by VTK's shader cache."""
        if options["features"] != self.options["features"]:
            self._set_program(options["features"])
        self.options = options
        self._set_uniforms()

    def _set_program(self, features: frozenset[str]) -> None:
        sp = self._actor.GetShaderProperty()
        sp.ClearFragmentShaderReplacement("//VTK::Light::Impl", True)
        impl = glsl.contour_fs_impl(features)
        sp.AddFragmentShaderReplacement("//VTK::Light::Impl", True, impl, False)

    def detach(self) -> None:
        """Remove everything :meth:`attach` added: the actor draws exactly as before."""
        if not self._attached:
            return
        self._attached = False
        if self._observer is not None:
            self._renderer.RemoveObserver(self._observer)
            self._observer = None
        sp = self._actor.GetShaderProperty()
        sp.ClearVertexShaderReplacement("//VTK::Normal::Dec", True)
        sp.ClearVertexShaderReplacement("//VTK::Normal::Impl", True)
        sp.ClearFragmentShaderReplacement("//VTK::Normal::Dec", True)
        sp.ClearFragmentShaderReplacement("//VTK::Light::Impl", True)
        fu = sp.GetFragmentCustomUniforms()
        for name in [*self.options["floats"], "sgColor", "sgOpacity"]:
            fu.RemoveUniform(name)
        vu = sp.GetVertexCustomUniforms()
        for name in ("sgHeightNum", "sgHeightDen"):
            vu.RemoveUniform(name)
        if self._mapped is not None:
            self._mapped.RemoveVertexAttributeMapping(_ATTRIBUTE)
            self._mapped = None

    # ------------------------------------------------------------------ per frame
    def _set_uniforms(self) -> None:
        fu = self._actor.GetShaderProperty().GetFragmentCustomUniforms()
        for name, value in self.options["floats"].items():
            fu.SetUniformf(name, value)
        fu.SetUniform3f("sgColor", self.options["color"])
        fu.SetUniformf("sgOpacity", self.options["opacity"])

    def _set_height_plane(self) -> None:
        """World height from the vertex's clip position: ``h = (n . c) / (d . c)`` with the
        rows of the inverse of the camera's composite projection (in float64 here), so the
        model matrix and VTK's shift of far-from-origin coordinates are both inside ``c``."""
        ren = self._renderer
        w, h = (int(v) for v in ren.GetSize())
        aspect = w / h if w > 0 and h > 0 else 1.0
        m = ren.GetActiveCamera().GetCompositeProjectionTransformMatrix(aspect, -1.0, 1.0)
        wcdc = np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])
        dcwc = np.linalg.inv(wcdc)
        axis = np.asarray(self.field.axis)
        num = axis @ dcwc[:3]
        vu = self._actor.GetShaderProperty().GetVertexCustomUniforms()
        vu.SetUniform4f("sgHeightNum", [float(v) for v in num])
        vu.SetUniform4f("sgHeightDen", [float(v) for v in dcwc[3]])

    def _map_attribute(self, renderer: Any = None) -> None:
        """Map the point array to the shader's attribute on the mapper that draws: the
        actor's own, or the polydata mapper a ``vtkDataSetMapper`` makes on its first render
        (made now, at the subplot's start, by one draw that the subplot's clear erases)."""
        if self.field.scalars is None:
            return
        pm = self._mapper
        if isinstance(pm, vtkDataSetMapper):
            pm = self._mapper.GetPolyDataMapper()
            if pm is None:
                if renderer is None:
                    return  # no context yet: the next subplot start makes it
                self._mapper.Render(renderer, self._actor)
                pm = self._mapper.GetPolyDataMapper()
                if pm is None:
                    return
        if pm is not self._mapped:
            pm.MapDataArrayToVertexAttribute(
                _ATTRIBUTE, self.field.scalars, vtkDataObject.FIELD_ASSOCIATION_POINTS, -1
            )
            self._mapped = pm

    def _on_start(self, renderer: Any, _event: str) -> None:
        if self.field.scalars is None:
            self._set_height_plane()
        elif self._mapped is None or (
            isinstance(self._mapper, vtkDataSetMapper)
            and self._mapper.GetPolyDataMapper() is not self._mapped
        ):
            self._map_attribute(renderer)
