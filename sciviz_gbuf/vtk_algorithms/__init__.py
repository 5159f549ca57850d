"""VTK pipeline algorithms: :func:`~sciviz_gbuf.capture` and the filters as VTK filters.

Each class is a :class:`~vtkmodules.util.vtkAlgorithm.VTKPythonAlgorithmBase` subclass, so it
chains with ``SetInputConnection`` and with plain VTK image filters, and VTK's demand-driven
pipeline re-executes it only when it, or something upstream of it, was modified.

- :class:`vtkGBufferCapture` (source, no input): a scene -> ``vtkImageData`` holding every
  G-buffer channel as a named point array, exactly :meth:`GBuffer.to_pyvista` (row 0 of the
  G-buffer is the top row, i.e. the *last* VTK row; the camera metadata travels in field data).
- Array filters (``vtkImageData`` -> ``vtkImageData``): the input's named point array, as an
  ``(H, W)`` or ``(H, W, k)`` image in G-buffer row order, goes through the numpy function;
  the output is a shallow copy of the input plus the result as a new named point array,
  which becomes the active scalars (what plain VTK image filters process).
  :data:`ARRAY_FILTERS` lists them.
- G-buffer filters (``vtkImageData`` -> ``vtkImageData``): the input must carry a whole
  G-buffer (the output of :class:`vtkGBufferCapture`, or of array filters after it, which keep
  it); it is rebuilt with :meth:`GBuffer.from_pyvista` and the function applied.
  :data:`GBUFFER_FILTERS` lists them. Their results are at the G-buffer's *output* size: for
  ``supersample == 1`` the output is the input plus the new array, for ``supersample > 1`` it
  is a new, smaller image holding only the new array (the full-size channels do not fit it).

Every keyword parameter of the wrapped function has a ``Set<Name>``/``Get<Name>`` pair
(``width`` -> ``SetWidth``, ``crease_angle`` -> ``SetCreaseAngle``), plus the generic
``SetParameter(name, value)`` / ``GetParameter(name)``. A setter calls ``Modified()`` only when
the value changes, and validates first: the function is run on a tiny synthetic input with the
new value, so a bad value raises :class:`~sciviz_gbuf.errors.InputError` from the setter and
leaves the algorithm unchanged.

Errors while the pipeline executes (say an input array that does not exist) cannot propagate
through VTK's C++ executive as Python exceptions. They are caught in ``RequestData``, the output
is emptied (never stale), VTK reports the failed request on its output window, the exception is
kept in ``last_error`` and it is raised again by ``Update()`` of any algorithm of this module
at or downstream of the failing one (even through plain VTK filters in between). When a plain
VTK algorithm is updated instead, call :func:`raise_pipeline_errors` on it.

``execution_count`` counts ``RequestData`` calls (for checking laziness).

The classes (:data:`ALGORITHMS` maps the function names to them): ``vtkGBufferCapture``, and
one filter class per entry of the filters registry (:data:`sciviz_gbuf.filters.registry.FILTERS`),
named ``vtkGBuffer`` + the function name in CamelCase (``contour_lines`` ->
``vtkGBufferContourLines``); the table below is generated from the registry.

The result array is named after the function (``SetOutputArrayName`` to change it). Array
filters pass the input's ``"mask"`` array (the G-buffer coverage) as ``mask=`` when there is
one (``SetMaskArrayName(None)`` to stop that); ``SetInputComponent(i)`` takes one component of
a vector array, e.g. ``SetInputArrayName("world")`` + ``SetInputComponent(2)`` for heights.

Image extents are announced before execution (``RequestInformation``), as VTK image filters
downstream need: the capture's from its window size and supersampling, a G-buffer filter's
output size from the supersampling found upstream (through this module's algorithms, plain VTK
filters assumed to keep the size, or data given with ``SetInputData``). If it cannot be found
and the G-buffer turns out supersampled, the G-buffer filter fails with :class:`InputError`
rather than hand VTK an image of another size than announced.

As with any VTK algorithm, an output port does not keep its algorithm alive: keep a Python
reference to each algorithm (``b.SetInputConnection(A().GetOutputPort())`` crashes).

The algorithms do not watch the scene given to :meth:`vtkGBufferCapture.SetScene`: after
editing the datasets, actors or camera in it, call ``Modified()`` on the capture.

Examples
--------
>>> import pyvista as pv
>>> from sciviz_gbuf.vtk_algorithms import vtkGBufferCapture, vtkGBufferEdgeMap
>>> cap = vtkGBufferCapture()
>>> cap.SetScene(pv.Sphere())
>>> cap.SetWindowSize(64, 48)
>>> edges = vtkGBufferEdgeMap()
>>> edges.SetInputConnection(cap.GetOutputPort())
>>> edges.SetWidth(2)
>>> edges.Update()
True
>>> pv.wrap(edges.GetOutput()).point_data["edge_map"].shape
(3072, 4)
"""

from __future__ import annotations

from ..filters.registry import FILTERS
from ._capture import vtkGBufferCapture
from ._pipeline import (
    ArrayFilter,
    GBufferAlgorithm,
    GBufferFilter,
    ParamFilter,
    camel,
    fill_levels,
    make_filter_class,
    raise_pipeline_errors,
)

vtkGBufferCapture.__module__ = __name__  # shown (and pickled) under its public path


def _class_name(name: str) -> str:
    return "vtkGBuffer" + camel(name)


# One class per entry of the filters registry, bound as a module attribute of its own name.
_CLASSES: dict[str, type[ParamFilter]] = {}
for _name, _f in FILTERS.items():
    _CLASSES[_name] = make_filter_class(
        _class_name(_name),
        ArrayFilter if _f.takes == "array" else GBufferFilter,
        _f.func,
        default_input=_f.default_input,
        dry_components=_f.components,
        dry_fill=fill_levels if _f.needs_levels else None,
    )
    globals()[_CLASSES[_name].__name__] = _CLASSES[_name]

#: Array filters by function name: ``vtkImageData`` array -> new array (same size).
ARRAY_FILTERS: dict[str, type[ParamFilter]] = {
    n: c for n, c in _CLASSES.items() if FILTERS[n].takes == "array"
}
#: G-buffer filters by function name: whole G-buffer image -> new array (output size).
GBUFFER_FILTERS: dict[str, type[ParamFilter]] = {
    n: c for n, c in _CLASSES.items() if FILTERS[n].takes == "gbuffer"
}
#: Every algorithm class by name (``"capture"`` and the function names).
ALGORITHMS: dict[str, type[GBufferAlgorithm]] = {
    "capture": vtkGBufferCapture,
    **ARRAY_FILTERS,
    **GBUFFER_FILTERS,
}

__all__ = [
    "ALGORITHMS",
    "ARRAY_FILTERS",
    "GBUFFER_FILTERS",
    "raise_pipeline_errors",
    "vtkGBufferCapture",
    *sorted(c.__name__ for c in _CLASSES.values()),
]


def _class_table() -> str:
    rows = [("vtkGBufferCapture", ":func:`sciviz_gbuf.capture`", "(source)")]
    for name, f in FILTERS.items():
        where = "G-buffer" if f.takes == "gbuffer" else f"``{f.default_input}``"
        if f.takes == "array" and f.default_input is None:
            where = "active scalars"
        rows.append((_CLASSES[name].__name__, f":func:`~sciviz_gbuf.filters.{name}`", where))
    widths = [max(len(r[i]) for r in rows) for i in range(3)]
    rule = "  ".join("=" * w for w in widths)
    head = ("class", "wraps", "default input array")
    lines = [rule, "  ".join(h.ljust(w) for h, w in zip(head, widths, strict=True)).rstrip(), rule]
    lines += ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip() for r in rows]
    return "\n".join([*lines, rule])


if __doc__:  # None under python -OO
    __doc__ += "\nGenerated class table\n---------------------\n\n" + _class_table() + "\n"
