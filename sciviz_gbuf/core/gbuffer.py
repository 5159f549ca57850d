"""The G-buffer: per-pixel geometric properties of a rendered scene (Saito & Takahashi 1990 §2).

A :class:`GBuffer` is captured once and re-used for any number of enhancements; it saves and
loads losslessly (``.npz`` or VTK ``.vti``) so enhancement can be re-run without re-rendering.
"""

from __future__ import annotations

import json
import os
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from tokenize import TokenError
from zipfile import BadZipFile

import numpy as np

from .. import _validate
from .._atomic import Part, atomic_output, native_stderr, one_line
from .._validate import LIMITS
from ..errors import InputError
from ._block_mean_kernels import block_mean
from .camera import CameraInfo

__all__ = ["FORMAT_VERSION", "META_KEY", "GBuffer", "check_gbuffer"]

FORMAT_VERSION = 1
_SCALAR_PREFIX = "scalars:"
_LAYER_PREFIX = "layer"
META_KEY = "sciviz_gbuf_meta"
# (name, dtype, trailing shape) of the fixed channels
_CHANNELS: tuple[tuple[str, type, tuple[int, ...]], ...] = (
    ("depth", np.float32, ()),
    ("sz", np.float32, ()),
    ("normal", np.float32, (3,)),
    ("world", np.float32, (3,)),
    ("object_id", np.int32, ()),
    ("cell_id", np.int64, ()),
    ("mask", np.bool_, ()),
)


@dataclass(eq=False)
class GBuffer:
    """Float32 G-buffers of one view (see ``DESIGN.md`` for the contract).

    Attributes
    ----------
    depth : (H, W) float32
        Linear eye-space distance along the viewing axis; NaN on background.
    sz : (H, W) float32
        Saito's perspective depth ``d**2 / (w z_v)`` (1990 Eq. 6), in pixels; larger is nearer.
    normal : (H, W, 3) float32
        Unit eye-space normals (x right, y up, z towards the viewer), turned to the viewer's side
        of the surface.
    world : (H, W, 3) float32
        World coordinates of the visible surface point.
    object_id : (H, W) int32
        Index of the dataset in the scene; -1 on background.
    cell_id : (H, W) int64
        Cell of that dataset; -1 on background.
    mask : (H, W) bool
        Coverage.
    camera : CameraInfo
        The camera that made the buffers (its ``window_size`` is the buffers' size).
    uv : (H, W, 2) float32 or None
        Texture coordinates where the data has them (NaN elsewhere).
    scalars : dict of str to ndarray
        Requested point/cell arrays, (H, W) float32 (or (H, W, k) for k-component arrays).
    supersample : int
        Factor by which the buffers exceed the output image size (see :meth:`downsample`).
    object_names : list of str
        Label of each object id.
    layers : tuple of GBuffer
        The surfaces behind this one along each pixel's ray, nearest first
        (``capture(layers=k)``: ``k - 1`` of them, each with the same channels and camera; a
        pixel with fewer surfaces behind it is background there). Empty by default.

    Row 0 of every array is the top image row, as in a PNG.
    """

    depth: np.ndarray
    sz: np.ndarray
    normal: np.ndarray
    world: np.ndarray
    object_id: np.ndarray
    cell_id: np.ndarray
    mask: np.ndarray
    camera: CameraInfo
    uv: np.ndarray | None = None
    scalars: dict[str, np.ndarray] = field(default_factory=dict)
    supersample: int = 1
    object_names: list[str] = field(default_factory=list)
    layers: tuple[GBuffer, ...] = ()

    # ------------------------------------------------------------------ basics
    @property
    def shape(self) -> tuple[int, int]:
        """``(H, W)`` of the buffers."""
        return tuple(self.depth.shape)  # type: ignore[return-value]

    @property
    def output_shape(self) -> tuple[int, int]:
        """``(H, W)`` of the image after :meth:`downsample`."""
        h, w = self.shape
        return h // self.supersample, w // self.supersample

    def channels(self) -> dict[str, np.ndarray]:
        """All arrays by name (fixed channels, ``uv`` if present, ``scalars:<name>``)."""
        out = {name: getattr(self, name) for name, _, _ in _CHANNELS}
        if self.uv is not None:
            out["uv"] = self.uv
        for k, v in self.scalars.items():
            out[_SCALAR_PREFIX + k] = v
        for i, layer in enumerate(self.layers, start=2):
            for k, v in layer.channels().items():
                out[f"{_LAYER_PREFIX}{i}:{k}"] = v
        return out

    def world_normal(self) -> np.ndarray:
        """Normals rotated back to world coordinates, (H, W, 3) float32."""
        rot = self.camera.view_matrix_array[:3, :3]
        return (self.normal.astype(np.float64) @ rot).astype(np.float32)

    def downsample(self, image: np.ndarray) -> np.ndarray:
        """Reduce an image of this buffer's size to the output size (antialiasing).

        Float and bool images are box-filtered: each output pixel is the mean of its
        ``k x k`` samples, NaN samples left out (all-NaN stays NaN); a bool mask becomes
        fractional coverage. Integer images (ids) cannot be averaged: the sample nearest the
        block centre is taken.

        ``supersample`` must be an integer in [1, ``LIMITS["supersample"]`` = 8] (a G-buffer
        made by hand may carry anything there), and ``image`` a 2-D or 3-D array.
        """
        k = _validate.count(self.supersample, "gb.supersample", "supersample")
        img = np.asarray(image)
        if img.ndim not in (2, 3) or img.dtype.kind not in "biuf":
            raise InputError(
                f"image: expected an (H, W) or (H, W, C) numeric array, got shape {img.shape} "
                f"dtype {img.dtype}"
            )
        if img.shape[:2] != self.shape:
            raise InputError(
                f"image: expected shape {self.shape} (this G-buffer), got {img.shape[:2]}"
            )
        if k == 1:
            return img.copy()
        if np.issubdtype(img.dtype, np.integer):
            return img[k // 2 :: k, k // 2 :: k].copy()
        return block_mean(img, k, self.output_shape)

    def __repr__(self) -> str:
        h, w = self.shape
        extra = (["uv"] if self.uv is not None else []) + [_SCALAR_PREFIX + k for k in self.scalars]
        return (
            f"GBuffer({w}x{h}, supersample={self.supersample}, "
            f"coverage={self.mask.mean():.1%}, objects={len(self.object_names)}, "
            f"projection={'parallel' if self.camera.parallel_projection else 'perspective'}"
            + (f", extra={extra}" if extra else "")
            + (f", layers={1 + len(self.layers)}" if self.layers else "")
            + ")"
        )

    # ------------------------------------------------------------------ meta
    def _meta(self) -> str:
        return json.dumps(
            {
                "format": "sciviz_gbuf",
                "version": FORMAT_VERSION,
                "camera": json.loads(self.camera.to_json()),
                "supersample": self.supersample,
                "object_names": list(self.object_names),
                "scalars": list(self.scalars),
                "layers": len(self.layers),
            }
        )

    @classmethod
    def _from_arrays(cls, arrays: dict[str, np.ndarray], meta_text: str, path: str) -> GBuffer:
        try:
            meta = json.loads(meta_text)
            if meta.get("format") != "sciviz_gbuf":
                raise ValueError("not a sciviz_gbuf G-buffer")
            if int(meta["version"]) > FORMAT_VERSION:
                raise ValueError(f"format version {meta['version']} is newer than this package")
            camera = CameraInfo.from_json(json.dumps(meta["camera"]))
            supersample = meta.get("supersample", 1)
            if isinstance(supersample, bool) or not isinstance(supersample, int):
                raise ValueError(f"supersample: expected an integer, got {supersample!r}")
        except (ValueError, KeyError, TypeError, AttributeError) as exc:
            raise InputError(f"{path}: not a valid G-buffer file ({exc})") from exc
        _check_camera(camera, path)
        if not 1 <= supersample <= LIMITS["supersample"]:
            raise InputError(
                f"{path}: supersample: expected 1 to {LIMITS['supersample']:g}, got {supersample}"
            )
        missing = [name for name, _, _ in _CHANNELS if name not in arrays]
        if missing:
            raise InputError(f"{path}: G-buffer file lacks channel(s) {missing}")
        if np.ndim(arrays["depth"]) != 2:
            raise InputError(f"{path}: channel 'depth' has shape {np.shape(arrays['depth'])}")
        h, w = arrays["depth"].shape[:2]
        cw, ch = camera.window_size
        # The camera records the window as rendered: supersample times the output size.
        if (h, w) != (ch, cw) or h % supersample or w % supersample:
            raise InputError(
                f"{path}: channels of {w}x{h} pixels do not match the camera's {cw}x{ch} "
                f"window, or are not a multiple of supersample {supersample}"
            )
        kw: dict[str, np.ndarray] = {}
        for name, dtype, trailing in _CHANNELS:
            a = np.asarray(arrays[name])
            if a.shape != (h, w, *trailing):
                raise InputError(
                    f"{path}: channel {name!r} has shape {a.shape}, expected {(h, w, *trailing)}"
                )
            kw[name] = np.ascontiguousarray(a.astype(dtype, copy=False))
        scalars = {}
        for name in meta.get("scalars", []):
            key = _SCALAR_PREFIX + name
            if key not in arrays:
                raise InputError(f"{path}: G-buffer file lacks scalar {name!r}")
            scalars[name] = np.ascontiguousarray(arrays[key])
        uv = np.ascontiguousarray(arrays["uv"]) if "uv" in arrays else None
        n_layers = meta.get("layers", 0)
        if isinstance(n_layers, bool) or not isinstance(n_layers, int):
            raise InputError(f"{path}: layers: expected an integer, got {n_layers!r}")
        if not 0 <= n_layers < LIMITS["layers"]:
            raise InputError(
                f"{path}: layers: expected 0 to {LIMITS['layers'] - 1:g} behind the first, "
                f"got {n_layers}"
            )
        behind = []
        sub_meta = json.dumps({**meta, "layers": 0})
        for i in range(2, n_layers + 2):
            prefix = f"{_LAYER_PREFIX}{i}:"
            sub = {k[len(prefix) :]: v for k, v in arrays.items() if k.startswith(prefix)}
            if not sub:
                raise InputError(f"{path}: G-buffer file lacks layer {i}")
            behind.append(cls._from_arrays(sub, sub_meta, f"{path} (layer {i})"))
        return cls(
            camera=camera,
            uv=uv,
            scalars=scalars,
            supersample=supersample,
            object_names=list(meta.get("object_names", [])),
            layers=tuple(behind),
            **kw,
        )

    # ------------------------------------------------------------------ io
    def save(self, path: str | os.PathLike) -> Path:
        """Write to ``.npz`` (NumPy, compressed) or ``.vti`` (VTK XML image); lossless.

        The file is complete or absent: it is written to a temporary file beside it, checked
        (the bytes on disk are the bytes written; VTK's writer reported no error and wrote the
        closing tag) and renamed.

        Returns
        -------
        pathlib.Path
            The path written.

        Raises
        ------
        InputError
            Another suffix, or a folder that does not exist.
        OutputError
            The file could not be written completely (disk full, file too large, no
            permission, interrupted); nothing new is left under its name.
        """
        p = Path(path)
        suffix = p.suffix.lower()
        if suffix not in (".npz", ".vti"):
            raise InputError(f"{p}: G-buffers are saved as .npz or .vti, not {suffix!r}")
        if not p.parent.is_dir():
            raise InputError(f"{p}: no such directory {str(p.parent)!r}")
        with atomic_output(path) as part:
            if suffix == ".npz":
                arrays = self.channels()
                with open(part.path, "wb") as f:
                    np.savez_compressed(f, **arrays, **{META_KEY: np.array(self._meta())})
                    part.expected_size = f.tell()
            else:
                _write_vti(self.to_pyvista(), part)
        return p

    @classmethod
    def load(cls, path: str | os.PathLike) -> GBuffer:
        """Read a file written by :meth:`save`."""
        p = Path(path)
        if not p.is_file():
            raise InputError(f"{p}: no such G-buffer file")
        suffix = p.suffix.lower()
        if suffix == ".npz":
            try:
                with np.load(p, allow_pickle=False) as z:
                    arrays = {k: z[k] for k in z.files}
            # (numpy's header parser raises TokenError on damaged bytes)
            except (
                OSError,
                ValueError,
                EOFError,
                KeyError,
                BadZipFile,
                zlib.error,
                TokenError,
            ) as exc:
                raise InputError(f"{p}: cannot read as .npz ({one_line(str(exc))})") from exc
            except MemoryError as exc:  # a lying array header
                raise InputError(
                    f"{p}: an array in it declares more data than fits in memory"
                ) from exc
            if META_KEY not in arrays:
                raise InputError(f"{p}: not a sciviz_gbuf G-buffer (no {META_KEY!r} record)")
            return cls._from_arrays(arrays, str(arrays.pop(META_KEY)), str(p))
        if suffix == ".vti":
            img = _read_vti(p)
            return cls.from_pyvista(img, source=str(p))
        raise InputError(f"{p}: G-buffers are loaded from .npz or .vti, not {suffix!r}")

    def to_pyvista(self):
        """A ``pyvista.ImageData`` holding every channel as a point array (one point a pixel).

        VTK images start at the bottom row, so rows are flipped; pixel (i, j) of the arrays is
        point (j, H-1-i). The camera and metadata are kept in field data.
        """
        import pyvista as pv

        h, w = self.shape
        img = pv.ImageData(dimensions=(w, h, 1))
        for name, arr in self.channels().items():
            a = np.asarray(arr)
            if a.dtype == np.bool_:
                a = a.astype(np.uint8)
            flat = a[::-1].reshape(h * w, *a.shape[2:])
            img.point_data[name] = np.ascontiguousarray(flat)
        img.field_data[META_KEY] = np.array([self._meta()])
        return img

    @classmethod
    def from_pyvista(cls, image, *, source: str = "image") -> GBuffer:
        """Inverse of :meth:`to_pyvista`."""
        if META_KEY not in image.field_data:
            raise InputError(f"{source}: not a sciviz_gbuf G-buffer (no {META_KEY!r} field data)")
        w, h, _ = image.dimensions
        arrays = {}
        for name in image.point_data.keys():
            a = np.asarray(image.point_data[name])
            arrays[name] = a.reshape(h, w, *a.shape[1:])[::-1]
        meta = image.field_data[META_KEY]
        return cls._from_arrays(arrays, str(meta[0]), source)


def _read_vti(path: Path):
    """A ``.vti`` file as a ``pyvista.ImageData``, or an InputError naming it.

    VTK's XML reader reports a damaged file only to its log (through PyVista's output window,
    coloured, several lines) and returns an empty image: the log is switched off for the read
    and the outcome judged from the reader's error code and output instead."""
    import pyvista as pv
    from vtkmodules.vtkCommonCore import vtkObject
    from vtkmodules.vtkIOXML import vtkXMLImageDataReader

    reader = vtkXMLImageDataReader()
    shown = vtkObject.GetGlobalWarningDisplay()
    vtkObject.GlobalWarningDisplayOff()
    try:
        with native_stderr() as logged:
            ok = reader.CanReadFile(str(path))
            if ok:
                reader.SetFileName(str(path))
                reader.Update()
    except UnicodeError as exc:  # VTK takes UTF-8 file names only
        raise InputError(f"{path}: VTK cannot open a file whose name is not UTF-8") from exc
    finally:
        vtkObject.SetGlobalWarningDisplay(shown)
    image = reader.GetOutput() if ok else None
    if not ok or reader.GetErrorCode() != 0 or image is None or image.GetNumberOfPoints() == 0:
        detail = f" ({one_line(' '.join(logged))})" if logged else ""
        raise InputError(f"{path}: not a readable VTK XML image (.vti){detail}")
    return pv.wrap(image)


def _check_camera(cam: CameraInfo, path: str) -> None:
    """A loaded camera record that every filter can trust: finite, a real view, a window."""
    numbers = [
        *cam.position,
        *cam.focal_point,
        *cam.view_up,
        cam.view_angle,
        cam.parallel_scale,
        *cam.clipping_range,
        *cam.view_matrix,
        *cam.projection_matrix,
    ]
    lengths = (len(cam.position), len(cam.focal_point), len(cam.view_up), len(cam.clipping_range))
    if lengths != (3, 3, 3, 2) or len(cam.view_matrix) != 16 or len(cam.projection_matrix) != 16:
        raise InputError(
            f"{path}: camera record: expected 3-vectors, a clipping range, 4x4 matrices"
        )
    if not np.isfinite(np.asarray(numbers, dtype=np.float64)).all():
        raise InputError(f"{path}: camera record holds NaN or infinite values")
    near, far = cam.clipping_range
    w, h = cam.window_size
    side = LIMITS["image_side"]
    if not (0 < near < far) or not (0 < cam.view_angle < 180) or cam.parallel_scale <= 0:
        raise InputError(
            f"{path}: camera record: expected 0 < near < far, a view angle in (0, 180) and a "
            f"parallel scale > 0, got {cam.clipping_range}, {cam.view_angle}, {cam.parallel_scale}"
        )
    if not (1 <= w <= side and 1 <= h <= side):
        raise InputError(f"{path}: camera record: window size {w}x{h} is not 1..{side:g} a side")
    if np.linalg.norm(np.subtract(cam.focal_point, cam.position)) == 0:
        raise InputError(f"{path}: camera record: the eye is at its focal point")


def _write_vti(image, part: Part) -> None:
    """``image`` into ``part.path`` as PyVista writes ``.vti`` (binary, zlib), with VTK's
    errors checked: VTK's writers report them only to its log and the return value of
    ``Write`` (a full disk leaves a cut file and an error code, no exception)."""
    from vtkmodules.util.misc import calldata_type
    from vtkmodules.util.vtkConstants import VTK_STRING
    from vtkmodules.vtkCommonCore import vtkCommand
    from vtkmodules.vtkCommonMisc import vtkErrorCode
    from vtkmodules.vtkIOXML import vtkXMLImageDataWriter

    messages: list[str] = []

    @calldata_type(VTK_STRING)
    def on_error(_obj, _event, text=None) -> None:
        messages.append(str(text or ""))

    writer = vtkXMLImageDataWriter()
    writer.SetFileName(str(part.path))
    writer.SetInputData(image)
    writer.SetDataModeToBinary()
    writer.SetCompressorTypeToZLib()
    # An observer takes the writer's error text instead of VTK's log; what the pipeline
    # prints about the failure is captured, and left out of the message (the error code says
    # it in one line).
    writer.AddObserver(vtkCommand.ErrorEvent, on_error)
    writer.GetExecutive().AddObserver(vtkCommand.ErrorEvent, on_error)
    with part.native(fold=False):
        ok = writer.Write()
    code = writer.GetErrorCode()
    if ok != 1 or code != 0:
        # The error code is errno's (or VTK's own) in one line; else the first message.
        reason = vtkErrorCode.GetStringFromErrorCode(code) if code else ""
        part.fail(reason or next((m for m in messages if m.strip()), "VTK's writer failed"))
    # The last bytes of a whole VTK XML file: a check that the stream was not cut short.
    with open(part.path, "rb") as f:
        f.seek(max(0, part.path.stat().st_size - 64))
        if b"</VTKFile>" not in f.read():
            part.fail("VTK's file is incomplete")


def check_gbuffer(gb: object) -> GBuffer:
    """``gb`` itself if it is a :class:`GBuffer`, else an :class:`InputError` naming it (the
    input check of every function that works on a whole G-buffer)."""
    if not isinstance(gb, GBuffer):
        raise InputError(
            f"gb: expected a sciviz_gbuf.GBuffer (from capture() or GBuffer.load()), "
            f"got {type(gb).__name__}"
        )
    return gb
