"""The generic machinery of :mod:`sciviz_gbuf.vtk_algorithms`: a ``VTKPythonAlgorithmBase``
base that keeps errors and execution counts, array <-> ``vtkImageData`` conversion, and the
parameterised filter classes made from a numpy function (validated ``Set<Name>`` setters that
call ``Modified()`` only on a change, dry runs on a tiny input)."""

from __future__ import annotations

import inspect
import json
from collections.abc import Callable
from typing import Any

import numpy as np
import pyvista as pv
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.util.vtkAlgorithm import VTKPythonAlgorithmBase
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.vtkCommonExecutionModel import vtkAlgorithm, vtkStreamingDemandDrivenPipeline
from vtkmodules.vtkRenderingCore import vtkCamera

from ..core.camera import CameraInfo
from ..core.gbuffer import META_KEY, GBuffer
from ..errors import InputError

__all__ = [
    "SDDP",
    "ArrayFilter",
    "GBufferAlgorithm",
    "GBufferFilter",
    "ParamFilter",
    "camel",
    "fill_levels",
    "freeze",
    "make_filter_class",
    "raise_pipeline_errors",
    "same_value",
]

SDDP = vtkStreamingDemandDrivenPipeline


# ---------------------------------------------------------------------------- helpers
def freeze(value: Any) -> Any:
    """A hashable, comparable form of a parameter value (sequences and arrays -> tuples)."""
    if isinstance(value, np.ndarray):
        return freeze(value.tolist())
    if isinstance(value, (list, tuple)):
        return tuple(freeze(v) for v in value)
    if isinstance(value, np.generic):
        return value.item()
    return value


def same_value(a: Any, b: Any) -> bool:
    # NaN != NaN would make "set to the current value" look like a change: compare the frozen
    # forms, treating identical NaN positions as equal
    fa, fb = freeze(a), freeze(b)
    if fa is None or fb is None:  # np.asarray(None, float) is NaN: keep None distinct
        return fa is fb
    try:
        return bool(fa == fb) or (
            np.asarray(fa, dtype=float).shape == np.asarray(fb, dtype=float).shape
            and bool(np.array_equal(np.asarray(fa, float), np.asarray(fb, float), equal_nan=True))
        )
    except (TypeError, ValueError):
        return False


def camel(name: str) -> str:
    return "".join(part[:1].upper() + part[1:] for part in name.split("_"))


def _image_of(data: object, what: str) -> vtkImageData:
    if not isinstance(data, vtkImageData):
        raise InputError(f"{what}: expected a vtkImageData input, got {type(data).__name__}")
    dims = data.GetDimensions()
    if dims[2] != 1:
        raise InputError(f"{what}: expected a 2-D image (one slice), got dimensions {dims}")
    return data


def _read_array(image: vtkImageData, name: str | None, what: str) -> tuple[np.ndarray, str]:
    """Point array ``name`` (None: the active scalars) as (H, W[, k]), row 0 on top."""
    pd = image.GetPointData()
    arr = pd.GetArray(name) if name is not None else pd.GetScalars()
    if arr is None:
        have = [pd.GetArrayName(i) for i in range(pd.GetNumberOfArrays())]
        wanted = repr(name) if name is not None else "active scalars"
        raise InputError(f"{what}: the input has no point array {wanted}; it has {have}")
    w, h, _ = image.GetDimensions()
    a = vtk_to_numpy(arr)
    # VTK stores x fastest from the bottom row up; G-buffer images have row 0 on top
    return a.reshape(h, w, *a.shape[1:])[::-1], arr.GetName() or ""


def _write_array(image: vtkImageData, name: str, values: np.ndarray) -> None:
    """Add ``values`` (H, W[, k]), row 0 on top, as point array ``name`` of ``image``."""
    a = np.asarray(values)
    if a.dtype == np.bool_:
        a = a.astype(np.uint8)
    w, h, _ = image.GetDimensions()
    if a.shape[:2] != (h, w):
        raise InputError(f"{name}: result has shape {a.shape[:2]}, the image is {(h, w)}")
    flat = np.ascontiguousarray(a[::-1].reshape(h * w, *a.shape[2:]))
    vtk_arr = numpy_to_vtk(flat, deep=1)
    vtk_arr.SetName(name)
    # active scalars: plain VTK image filters (vtkImageShiftScale, ...) process those
    image.GetPointData().SetScalars(vtk_arr)


def _upstream(alg: vtkAlgorithm) -> list[vtkAlgorithm]:
    out = []
    for port in range(alg.GetNumberOfInputPorts()):
        for c in range(alg.GetNumberOfInputConnections(port)):
            up = alg.GetInputAlgorithm(port, c)
            if up is not None:
                out.append(up)
    return out


def raise_pipeline_errors(alg: vtkAlgorithm) -> None:
    """Raise the error of the most upstream algorithm of this module that failed, if any.

    Walks ``alg`` and everything upstream of it (through plain VTK algorithms too). Use after
    ``Update()`` of a plain VTK algorithm fed by this module's algorithms; their own
    ``Update()`` does it already.
    """
    seen: set[int] = set()

    def walk(a: vtkAlgorithm) -> None:
        key = id(a)  # the wrapper of a live algorithm is unique, so id() identifies it
        if key in seen:
            return
        seen.add(key)
        for up in _upstream(a):
            walk(up)
        err = getattr(a, "last_error", None)
        if err is not None:
            raise err

    walk(alg)


def _meta_supersample(data: object) -> int | None:
    """``supersample`` recorded in a G-buffer image's field data, or None."""
    if not isinstance(data, vtkImageData):
        return None
    arr = data.GetFieldData().GetAbstractArray(META_KEY)
    if arr is None or arr.GetNumberOfValues() == 0:
        return None
    try:
        return int(json.loads(arr.GetValue(0)).get("supersample", 1))
    except (ValueError, TypeError, AttributeError):
        return None


def _upstream_supersample(alg: vtkAlgorithm) -> int | None:
    """Supersampling of the G-buffer flowing into ``alg``, known before anything executes.

    Follows the first input upstream, through plain VTK filters (assumed to keep the image
    size), to an algorithm of this module (which knows its output) or to data given with
    ``SetInputData`` (whose field data tells); None when it cannot be known.
    """
    a = alg
    for _ in range(1000):  # a pipeline is a DAG; the bound only guards against surprises
        if a.GetNumberOfInputPorts() == 0 or a.GetNumberOfInputConnections(0) == 0:
            return None
        up = a.GetInputAlgorithm(0, 0)
        if isinstance(up, GBufferAlgorithm):
            return up._supersample_hint()
        if up is None:
            return None
        if up.IsA("vtkTrivialProducer"):
            return _meta_supersample(up.GetOutputDataObject(0))
        a = up
    return None


# ---------------------------------------------------------------------------- base
class GBufferAlgorithm(VTKPythonAlgorithmBase):
    """Execution counting, error capture and error re-raising shared by all algorithms."""

    def __init__(self, n_inputs: int) -> None:
        VTKPythonAlgorithmBase.__init__(
            self,
            nInputPorts=n_inputs,
            inputType="vtkImageData",
            nOutputPorts=1,
            outputType="vtkImageData",
        )
        self.execution_count = 0
        self.last_error: Exception | None = None

    def Update(self, *args: Any) -> Any:
        """``vtkAlgorithm.Update``, then raise any error of this or an upstream execution."""
        result = VTKPythonAlgorithmBase.Update(self, *args)
        raise_pipeline_errors(self)
        return result

    def GetOutput(self, port: int = 0) -> vtkImageData:
        """The output image (like ``vtkImageAlgorithm.GetOutput``)."""
        return self.GetOutputDataObject(port)

    def SetInputData(self, *args: Any) -> None:
        """``SetInputData([port,] image)`` as on ``vtkImageAlgorithm`` (no upstream algorithm)."""
        self.SetInputDataObject(*args)

    def _supersample_hint(self) -> int | None:
        """Supersampling of the G-buffer this algorithm outputs, if known before executing."""
        return None

    def RequestData(self, request, inInfo, outInfo):
        self.execution_count += 1
        output = vtkImageData.GetData(outInfo, 0)
        try:
            self._execute(inInfo, output, outInfo.GetInformationObject(0))
        except Exception as exc:
            # a Python exception cannot cross VTK's C++ executive: keep it for Update() and
            # leave an empty output rather than the previous (stale) one
            self.last_error = exc
            output.Initialize()
            return 0
        self.last_error = None
        return 1

    def _execute(self, inInfo: Any, output: vtkImageData, out_info: Any) -> None:
        raise NotImplementedError


# ---------------------------------------------------------------------------- filters
def _dummy_gbuffer() -> GBuffer:
    """An 8x8 G-buffer of a plane facing the camera: a cheap input for validating parameters."""
    n = 8
    cam = vtkCamera()
    cam.SetPosition(0.0, 0.0, 10.0)
    cam.SetClippingRange(1.0, 20.0)
    info = CameraInfo.from_vtk(cam, (n, n))
    y, x = np.mgrid[0:n, 0:n].astype(np.float32)
    world = np.stack([x, -y, np.zeros_like(x)], axis=-1)
    depth = np.full((n, n), 10.0, np.float32)
    return GBuffer(
        depth=depth,
        sz=info.sz_from_depth(depth).astype(np.float32),
        normal=np.broadcast_to(np.array([0, 0, 1], np.float32), (n, n, 3)).copy(),
        world=world,
        object_id=np.zeros((n, n), np.int32),
        cell_id=np.zeros((n, n), np.int64),
        mask=np.ones((n, n), bool),
        camera=info,
    )


_DUMMY: dict[str, Any] = {}


def _dummy_input(kind: str, components: int) -> Any:
    key = f"{kind}{components}"
    if key not in _DUMMY:
        if kind == "gbuffer":
            _DUMMY[key] = _dummy_gbuffer()
        elif components == 3:
            v = np.array([0.3, 0.2, 0.9], np.float32)
            _DUMMY[key] = np.broadcast_to(v / np.linalg.norm(v), (8, 8, 3)).copy()
        else:
            y, x = np.mgrid[0:8, 0:8].astype(np.float32)
            _DUMMY[key] = x + 0.5 * y
    return _DUMMY[key]


class ParamFilter(GBufferAlgorithm):
    """Keyword parameters of a wrapped function: validated setters that call Modified()."""

    _func: Callable[..., np.ndarray]
    _kind = "array"  # or "gbuffer"
    _params: tuple[str, ...] = ()
    _dry_components = 1
    # parameters a dry run needs when the user has not set them (e.g. contour levels)
    _dry_fill: Callable[[dict[str, Any]], dict[str, Any]] = staticmethod(lambda p: p)

    def __init__(self) -> None:
        super().__init__(1)
        self._values: dict[str, Any] = {}
        self._output_name = self._func.__name__

    def SetParameter(self, name: str, value: Any) -> None:
        """Set keyword ``name`` of the wrapped function; ``None`` restores its default.

        Raises
        ------
        InputError
            Unknown name, or a value the function rejects (checked on a tiny input now).
        """
        if name not in self._params:
            raise InputError(
                f"{type(self).__name__}: unknown parameter {name!r}; expected one of "
                f"{list(self._params)}"
            )
        # compare with the value in effect (the default when unset): no change, no Modified()
        if value is None:
            if name not in self._values:
                return
        elif same_value(self.GetParameter(name), value):
            return
        candidate = dict(self._values)
        if value is None:
            candidate.pop(name, None)
        else:
            candidate[name] = value
        self._validate(name, candidate)
        self._values = candidate
        self.Modified()

    def GetParameter(self, name: str) -> Any:
        """The value set for ``name``, or the function's default."""
        if name not in self._params:
            raise InputError(f"{type(self).__name__}: unknown parameter {name!r}")
        if name in self._values:
            return self._values[name]
        return inspect.signature(self._func).parameters[name].default

    def GetParameters(self) -> dict[str, Any]:
        """The parameters set explicitly (what is passed to the function)."""
        return dict(self._values)

    def _validate(self, name: str, candidate: dict[str, Any]) -> None:
        def run(params: dict[str, Any]) -> Exception | None:
            try:
                self._func(_dummy_input(self._kind, self._dry_components), **self._dry_fill(params))
            except (InputError, TypeError, ValueError) as exc:
                return exc
            return None

        err = run(candidate)
        if err is None:
            return
        # blame the new value only if the parameters were fine without it (a parameter that is
        # only valid together with another one, set later, must not be refused now)
        before = run(self._values)
        if before is None or str(before) != str(err):
            if isinstance(err, InputError):
                raise InputError(f"{type(self).__name__}.{name}: {err}") from err
            raise InputError(f"{type(self).__name__}.{name}: bad value ({err})") from err

    def SetOutputArrayName(self, name: str) -> None:
        """Name of the result array (default: the function's name, e.g. ``"contour_lines"``)."""
        if not isinstance(name, str) or not name:
            raise InputError(f"output array name: expected a non-empty string, got {name!r}")
        if name != self._output_name:
            self._output_name = name
            self.Modified()

    def GetOutputArrayName(self) -> str:
        return self._output_name


def _add_accessors(cls: type[ParamFilter]) -> None:
    """``Set<Name>``/``Get<Name>`` for every keyword parameter of the wrapped function."""
    for pname in cls._params:
        suffix = camel(pname)

        def setter(self: ParamFilter, *value: Any, _p: str = pname) -> None:
            # SetLight(0, 0, 1) and SetLight((0, 0, 1)) both work, as in VTK
            self.SetParameter(_p, value[0] if len(value) == 1 else value)

        def getter(self: ParamFilter, _p: str = pname) -> Any:
            return self.GetParameter(_p)

        setter.__name__ = f"Set{suffix}"
        setter.__doc__ = f"Set ``{pname}`` of :func:`{cls._func.__name__}` (None: default)."
        getter.__name__ = f"Get{suffix}"
        getter.__doc__ = f"``{pname}`` of :func:`{cls._func.__name__}`."
        if not hasattr(cls, setter.__name__):
            setattr(cls, setter.__name__, setter)
            setattr(cls, getter.__name__, getter)


class ArrayFilter(ParamFilter):
    """A numpy image function on one named point array of a vtkImageData.

    ``SetInputArrayName(name)`` picks the array (None: the active scalars),
    ``SetInputComponent(i)`` one component of a vector array (e.g. 2: the world z),
    ``SetMaskArrayName(name)`` the coverage passed as ``mask=`` (default ``"mask"``, used when
    the input has it; None: no mask). The output is a shallow copy of the input with the
    result added as point array ``GetOutputArrayName()``, in the same pixel order.
    """

    _default_input: str | None = None

    def __init__(self) -> None:
        super().__init__()
        self._input_name = self._default_input
        self._component: int | None = None
        self._mask_name: str | None = "mask"

    def SetInputArrayName(self, name: str | None) -> None:
        if name is not None and (not isinstance(name, str) or not name):
            raise InputError(f"input array name: expected a non-empty string, got {name!r}")
        if name != self._input_name:
            self._input_name = name
            self.Modified()

    def GetInputArrayName(self) -> str | None:
        return self._input_name

    def SetInputComponent(self, component: int | None) -> None:
        if component is not None and (
            isinstance(component, bool)
            or not isinstance(component, (int, np.integer))
            or component < 0
        ):
            raise InputError(f"input component: expected an index >= 0 or None, got {component!r}")
        value = None if component is None else int(component)
        if value != self._component:
            self._component = value
            self.Modified()

    def SetMaskArrayName(self, name: str | None) -> None:
        if name is not None and (not isinstance(name, str) or not name):
            raise InputError(f"mask array name: expected a non-empty string, got {name!r}")
        if name != self._mask_name:
            self._mask_name = name
            self.Modified()

    def _supersample_hint(self) -> int | None:
        # same size as the input: whatever is upstream
        return _upstream_supersample(self)

    def _execute(self, inInfo: Any, output: vtkImageData, out_info: Any) -> None:
        what = type(self).__name__
        image = _image_of(vtkImageData.GetData(inInfo[0], 0), what)
        values, _ = _read_array(image, self._input_name, what)
        if self._component is not None:
            if values.ndim != 3 or self._component >= values.shape[2]:
                ncomp = values.shape[2] if values.ndim == 3 else 1
                raise InputError(
                    f"{what}: component {self._component} of array {self._input_name!r}, "
                    f"which has {ncomp}"
                )
            values = values[..., self._component]
        kwargs = dict(self._values)
        pd = image.GetPointData()
        if self._mask_name is not None and pd.GetArray(self._mask_name) is not None:
            kwargs["mask"] = _read_array(image, self._mask_name, what)[0].astype(bool)
        result = self._func(values, **kwargs)
        output.ShallowCopy(image)
        _write_array(output, self._output_name, result)


class GBufferFilter(ParamFilter):
    """A function of a whole GBuffer, rebuilt from the input image (capture's output)."""

    _kind = "gbuffer"

    def _supersample_hint(self) -> int | None:
        return 1

    def RequestInformation(self, request, inInfo, outInfo):
        # results are at the G-buffer's output size: announce it when the supersampling is
        # known from upstream (otherwise the input's extent, right for supersample == 1)
        k = _upstream_supersample(self)
        in_info = inInfo[0].GetInformationObject(0)
        if k and k > 1 and in_info.Has(SDDP.WHOLE_EXTENT()):
            ext = in_info.Get(SDDP.WHOLE_EXTENT())
            w, h = (ext[1] - ext[0] + 1) // k, (ext[3] - ext[2] + 1) // k
            outInfo.GetInformationObject(0).Set(SDDP.WHOLE_EXTENT(), (0, w - 1, 0, h - 1, 0, 0), 6)
        return 1

    def _execute(self, inInfo: Any, output: vtkImageData, out_info: Any) -> None:
        what = type(self).__name__
        image = _image_of(vtkImageData.GetData(inInfo[0], 0), what)
        gb = GBuffer.from_pyvista(pv.wrap(image), source=f"{what} input")
        result = self._func(gb, **self._values)
        if gb.supersample == 1:
            output.ShallowCopy(image)
        else:
            h, w = gb.output_shape
            announced = out_info.Get(SDDP.WHOLE_EXTENT())
            if announced is not None and tuple(announced) != (0, w - 1, 0, h - 1, 0, 0):
                # downstream VTK filters were promised another size: fail rather than let them
                # read past the image (supersampling was not known before executing)
                raise InputError(
                    f"{what}: the input G-buffer is supersampled x{gb.supersample}, which "
                    "could not be known before executing; connect this filter after "
                    "vtkGBufferCapture, this module's array filters or SetInputData"
                )
            output.SetDimensions(w, h, 1)
            output.SetOrigin(image.GetOrigin())
            output.SetSpacing(image.GetSpacing())
        _write_array(output, self._output_name, result)


def make_filter_class(
    name: str,
    base: type[ParamFilter],
    func: Callable[..., np.ndarray],
    *,
    default_input: str | None = None,
    dry_components: int = 1,
    dry_fill: Callable[[dict[str, Any]], dict[str, Any]] | None = None,
) -> type[ParamFilter]:
    # keyword parameters that are images come from arrays (mask), not setters
    params = tuple(
        p.name
        for p in inspect.signature(func).parameters.values()
        if p.kind is inspect.Parameter.KEYWORD_ONLY and p.name not in ("mask", "gradient", "out")
    )
    ns: dict[str, Any] = {
        "_func": staticmethod(func),
        "_params": params,
        "_dry_components": dry_components,
        "__doc__": (
            f":func:`sciviz_gbuf.filters.{func.__name__}` as a VTK filter "
            f"({'array' if base is ArrayFilter else 'G-buffer'} filter; output array "
            f"``{func.__name__!r}``).\n\nParameters (``Set<Name>``/``Get<Name>`` or "
            f"``SetParameter``): {', '.join(params)}."
        ),
        "__module__": __name__.rpartition(".")[0],  # the public sciviz_gbuf.vtk_algorithms
    }
    if base is ArrayFilter:
        ns["_default_input"] = default_input
        ns["__doc__"] += f" Default input array: {default_input or 'the active scalars'!s}."
    if dry_fill is not None:
        ns["_dry_fill"] = staticmethod(dry_fill)
    cls = type(name, (base,), ns)
    _add_accessors(cls)
    return cls


def fill_levels(p: dict[str, Any]) -> dict[str, Any]:
    # contour_lines / color_bands need interval= or levels=; dry-run with one if neither is set
    if "interval" not in p and "levels" not in p:
        return {**p, "interval": 1.0}
    return p
