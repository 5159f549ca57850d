"""The VTK pipeline algorithms: same results as the numpy functions, lazy re-execution, chaining
with plain VTK filters and errors that surface."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv
from vtkmodules.vtkImagingCore import vtkImageChangeInformation, vtkImageShiftScale
from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper, vtkRenderer

import sciviz_gbuf as sg
from sciviz_gbuf import filters as F
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.vtk_algorithms import (
    ALGORITHMS,
    ARRAY_FILTERS,
    GBUFFER_FILTERS,
    raise_pipeline_errors,
    vtkGBufferCapture,
    vtkGBufferContourLines,
    vtkGBufferEdgeMap,
    vtkGBufferLambert,
    vtkGBufferProfileEdges,
    vtkGBufferSobelGradient,
)

W, H = 96, 64


@pytest.fixture(scope="module")
def nut() -> pv.PolyData:
    return pv.examples.load_nut()


@pytest.fixture(scope="module")
def gbuf(nut) -> sg.GBuffer:
    return sg.capture(nut, window_size=(W, H))


def make_capture(scene, size=(W, H)) -> vtkGBufferCapture:
    cap = vtkGBufferCapture()
    cap.SetScene(scene)
    cap.SetWindowSize(*size)
    return cap


def chain(upstream, alg):
    alg.SetInputConnection(upstream.GetOutputPort())
    return alg


def image_array(alg_or_image, name: str) -> np.ndarray:
    """Point array ``name`` of an algorithm's output as (H, W[, k]) with row 0 on top."""
    img = alg_or_image.GetOutput() if hasattr(alg_or_image, "GetOutput") else alg_or_image
    img = pv.wrap(img)
    w, h, _ = img.dimensions
    a = np.asarray(img.point_data[name])
    return a.reshape(h, w, *a.shape[1:])[::-1]


def counts(*algs) -> list[int]:
    return [a.execution_count for a in algs]


# ---------------------------------------------------------------------------- equal to numpy
def test_capture_output_is_the_gbuffer(nut, gbuf):
    cap = make_capture(nut)
    cap.Update()
    out = pv.wrap(cap.GetOutput())
    assert out.dimensions == (W, H, 1)
    ref = gbuf.to_pyvista()
    assert sorted(out.point_data.keys()) == sorted(ref.point_data.keys())
    for name in ref.point_data.keys():
        assert np.array_equal(out.point_data[name], ref.point_data[name], equal_nan=True), name
    # the camera metadata travels along: the exact G-buffer comes back, row 0 on top
    back = sg.GBuffer.from_pyvista(out)
    assert back.camera == gbuf.camera
    assert np.array_equal(back.depth, gbuf.depth, equal_nan=True)
    assert np.array_equal(image_array(out, "world"), gbuf.world, equal_nan=True)
    # the top image row is VTK's last row
    top = np.asarray(out.point_data["depth"])[(H - 1) * W : H * W]
    assert np.array_equal(top, gbuf.depth[0], equal_nan=True)


def test_capture_to_edge_map_equals_numpy(nut, gbuf):
    cap = make_capture(nut)
    em = chain(cap, vtkGBufferEdgeMap())
    em.SetWidth(2)
    em.SetCreaseAngle(25)
    em.Update()
    got = image_array(em, "edge_map")
    ref = F.edge_map(gbuf, width=2, crease_angle=25)
    assert got.shape == (H, W, 4)
    assert ref[..., 3].max() == 1.0  # the test image has profiles
    assert np.array_equal(got, ref)
    # the input channels pass through unchanged (shallow copy plus the new array)
    assert np.array_equal(image_array(em, "sz"), gbuf.sz, equal_nan=True)


@pytest.mark.parametrize("source", ["world_z", "depth"])
def test_capture_to_contour_lines_equals_numpy(nut, gbuf, source):
    cap = make_capture(nut)
    cl = chain(cap, vtkGBufferContourLines())
    if source == "world_z":
        cl.SetInputArrayName("world")
        cl.SetInputComponent(2)
        field, interval = gbuf.world[..., 2], 0.5
    else:  # the default input array
        field, interval = gbuf.depth, 0.25
    cl.SetWidth(1.5)  # before the interval: valid once the interval is set too
    cl.SetInterval(interval)
    cl.Update()
    ref = F.contour_lines(field, interval=interval, width=1.5, mask=gbuf.mask)
    assert ref.max() == 1.0 and (ref > 0).mean() > 0.02  # lines are drawn
    assert np.array_equal(image_array(cl, "contour_lines"), ref)


def _ref_array_filters(g: sg.GBuffer) -> dict[str, tuple[dict, dict, np.ndarray]]:
    """name -> (setup, parameters, numpy result) for every array filter."""
    z = g.world[..., 2]
    m = g.mask
    zsetup = {"SetInputArrayName": "world", "SetInputComponent": 2}
    return {
        "sobel_gradient": ({}, {}, F.sobel_gradient(g.sz, mask=m)),
        "second_order": ({}, {}, F.second_order(g.sz, mask=m)),
        "c1_discontinuity": ({}, {}, F.c1_discontinuity(g.sz, mask=m)),
        "diagonal_depth_discontinuity": ({}, {}, F.diagonal_depth_discontinuity(g.sz, mask=m)),
        "diagonal_normal_discontinuity": (
            {},
            {},
            F.diagonal_normal_discontinuity(g.normal, mask=m),
        ),
        "normalize_gradient": (
            {"SetInputArrayName": "sz"},
            {"k_g": 5.0},
            F.normalize_gradient(g.sz, k_g=5.0, mask=m),
        ),
        "sky_view": (zsetup, {"directions": 8}, F.sky_view(z, directions=8, mask=m)),
        "openness": (zsetup, {"directions": 8}, F.openness(z, directions=8, mask=m)),
        "texture_shade": (zsetup, {"detail": 0.8}, F.texture_shade(z, detail=0.8, mask=m)),
        "local_relief": (zsetup, {"radius": 3.0}, F.local_relief(z, radius=3.0, mask=m)),
        "cast_shadows": (zsetup, {"azimuth": 200.0}, F.cast_shadows(z, azimuth=200.0, mask=m)),
        "contour_lines": ({}, {"interval": 0.3}, F.contour_lines(g.depth, interval=0.3, mask=m)),
        "hatching": (
            {},
            {"spacing": 4.0, "interval": 0.1},
            F.hatching(g.depth, spacing=4.0, interval=0.1, mask=m),
        ),
        "hillshade": (
            zsetup,
            {"azimuth": 270.0, "z_factor": 20.0},
            F.hillshade(z, azimuth=270.0, z_factor=20.0, mask=m),
        ),
        "color_bands": (zsetup, {"interval": 0.5}, F.color_bands(z, interval=0.5, mask=m)),
        "lambert": (
            {},
            {"light": (0.3, 0.4, 1.0), "ambient": 0.1},
            F.lambert(g.normal, light=(0.3, 0.4, 1.0), ambient=0.1, mask=m),
        ),
    }


def _ref_gbuffer_filters(g: sg.GBuffer) -> dict[str, tuple[dict, np.ndarray]]:
    return {
        "profile_edges": ({"depth_jump": 1.5}, F.profile_edges(g, depth_jump=1.5)),
        "internal_edges": ({"crease_angle": 20.0}, F.internal_edges(g, crease_angle=20.0)),
        "crease_edges": ({"width": 2.0}, F.crease_edges(g, width=2.0)),
        "id_edges": ({"ids": "cell"}, F.id_edges(g, ids="cell")),
        "edge_map": ({"operator": "c1"}, F.edge_map(g, operator="c1")),
        "reflection_lines": (
            {"axis": (1.0, 0.4, 0.0), "stripes": 12},
            F.reflection_lines(g, axis=(1.0, 0.4, 0.0), stripes=12),
        ),
        "isophotes": ({"interval": 15.0}, F.isophotes(g, interval=15.0)),
        "reflection_angle": (
            {"axis": (1.0, 0.4, 0.0)},
            F.reflection_angle(g, axis=(1.0, 0.4, 0.0)),
        ),
    }


def test_every_filter_equals_its_numpy_function(nut, gbuf):
    cap = make_capture(nut)
    arrays = _ref_array_filters(gbuf)
    gbufs = _ref_gbuffer_filters(gbuf)
    assert set(arrays) == set(ARRAY_FILTERS) and set(gbufs) == set(GBUFFER_FILTERS)
    assert set(ALGORITHMS) == {"capture"} | set(arrays) | set(gbufs)
    for name, (setup, params, ref) in arrays.items():
        alg = chain(cap, ARRAY_FILTERS[name]())
        for method, value in setup.items():
            getattr(alg, method)(value)
        for p, v in params.items():
            alg.SetParameter(p, v)
        alg.Update()
        got = image_array(alg, name)
        assert got.shape == ref.shape, name
        assert np.array_equal(got, ref, equal_nan=True), name
    for name, (params, ref) in gbufs.items():
        alg = chain(cap, GBUFFER_FILTERS[name]())
        for p, v in params.items():
            alg.SetParameter(p, v)
        alg.Update()
        assert np.array_equal(image_array(alg, name), ref, equal_nan=True), name
    assert cap.execution_count == 1  # one capture fed every registered filter


def test_explicit_setters_and_getters():
    cl = vtkGBufferContourLines()
    cl.SetInterval(5)
    cl.SetMajorInterval(25)
    assert cl.GetInterval() == 5 and cl.GetMajorInterval() == 25
    assert cl.GetWidth() == 1.0  # the function's default
    lam = vtkGBufferLambert()
    lam.SetLight(0, 1, 1)  # VTK style, same as SetLight((0, 1, 1))
    assert lam.GetLight() == (0, 1, 1)
    assert lam.GetParameters() == {"light": (0, 1, 1)}
    lam.SetLight(None)  # back to the default
    assert lam.GetParameters() == {}


# ---------------------------------------------------------------------------- laziness
def test_only_affected_algorithms_re_execute(nut, gbuf):
    cap = make_capture(nut)
    a = chain(cap, vtkGBufferLambert())  # A: shade from the normals
    b = chain(a, vtkGBufferContourLines())  # B: contour lines of A's shade
    b.SetInputArrayName("lambert")
    b.SetInterval(0.1)
    c = chain(cap, vtkGBufferEdgeMap())  # C: a sibling branch on the capture

    def update():
        b.Update()
        c.Update()

    update()
    assert counts(cap, a, b, c) == [1, 1, 1, 1]
    update()  # nothing changed
    assert counts(cap, a, b, c) == [1, 1, 1, 1]

    b.SetWidth(2)  # downstream parameter: only B
    update()
    assert counts(cap, a, b, c) == [1, 1, 2, 1]
    shade = F.lambert(gbuf.normal, mask=gbuf.mask)
    ref = F.contour_lines(shade, interval=0.1, width=2, mask=gbuf.mask)
    assert np.array_equal(image_array(b, "contour_lines"), ref)

    a.SetAmbient(0.3)  # upstream parameter: A and B, not C nor the capture
    update()
    assert counts(cap, a, b, c) == [1, 2, 3, 1]
    shade = F.lambert(gbuf.normal, ambient=0.3, mask=gbuf.mask)
    ref = F.contour_lines(shade, interval=0.1, width=2, mask=gbuf.mask)
    assert np.array_equal(image_array(b, "contour_lines"), ref)

    c.SetWidth(2)  # the sibling: only C
    update()
    assert counts(cap, a, b, c) == [1, 2, 3, 2]

    # setting every parameter to its current value changes nothing, not even the MTime
    mtimes = [x.GetMTime() for x in (cap, a, b, c)]
    cap.SetWindowSize(W, H)
    cap.SetWindowSize((W, H))
    cap.SetScene(nut)
    cap.SetSupersample(1)
    a.SetAmbient(0.3)
    a.SetParameter("ambient", 0.3)
    b.SetWidth(2.0)
    b.SetInterval(0.1)
    b.SetInputArrayName("lambert")
    c.SetWidth(2)
    update()
    assert [x.GetMTime() for x in (cap, a, b, c)] == mtimes
    assert counts(cap, a, b, c) == [1, 2, 3, 2]

    cap.SetWindowSize(80, 60)  # the source: everything downstream
    update()
    assert counts(cap, a, b, c) == [2, 3, 4, 3]
    assert b.GetOutput().GetDimensions() == (80, 60, 1)
    assert image_array(c, "edge_map").shape == (60, 80, 4)


def test_capture_camera_parameters_are_lazy(nut):
    cap = make_capture(nut, size=(48, 32))
    down = chain(cap, vtkGBufferSobelGradient())
    down.Update()
    cam = ((0.0, 0.0, 100.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    cap.SetCameraPosition(*cam)
    down.Update()
    assert counts(cap, down) == [2, 2]
    cap.SetCamera(cam)  # the same camera, given the other way
    cap.SetCameraPosition(*cam)
    down.Update()
    assert counts(cap, down) == [2, 2]
    cap.SetCamera("xy")
    down.Update()
    assert counts(cap, down) == [3, 3]
    cap.SetParallelProjection(True)
    down.Update()
    assert counts(cap, down) == [4, 4]
    g = sg.GBuffer.from_pyvista(pv.wrap(cap.GetOutput()))
    assert g.camera.parallel_projection


# ---------------------------------------------------------------------------- plain VTK
def test_chains_with_plain_vtk_filters(nut, gbuf):
    cap = make_capture(nut)
    sob = chain(cap, vtkGBufferSobelGradient())
    shift = vtkImageShiftScale()  # a plain VTK image filter on the named array
    shift.SetInputConnection(sob.GetOutputPort())
    shift.SetInputArrayToProcess(0, 0, 0, 0, "sobel_gradient")
    shift.SetScale(2.0)
    shift.SetShift(1.0)
    shift.SetOutputScalarTypeToFloat()
    shift.Update()
    out = shift.GetOutput()
    assert out.GetDimensions() == (W, H, 1)
    scaled = pv.convert_array(out.GetPointData().GetScalars())
    ref = F.sobel_gradient(gbuf.sz, mask=gbuf.mask)
    np.testing.assert_allclose(scaled.reshape(H, W)[::-1], (ref + 1.0) * 2.0, rtol=1e-6)

    # and back into this module's filters: the shifted scalars are the active scalars
    cl = vtkGBufferContourLines()
    cl.SetInputConnection(shift.GetOutputPort())
    cl.SetInputArrayName(None)
    cl.SetMaskArrayName(None)
    cl.SetInterval(0.5)
    cl.Update()
    field = scaled.reshape(H, W)[::-1]
    assert np.array_equal(image_array(cl, "contour_lines"), F.contour_lines(field, interval=0.5))
    # laziness holds through the plain filter
    before = counts(cap, sob, cl)
    cl.Update()
    assert counts(cap, sob, cl) == before
    sob.SetMaskArrayName(None)
    cl.Update()
    assert counts(cap, sob, cl) == [before[0], before[1] + 1, before[2] + 1]


def test_supersampled_gbuffer_filter_announces_output_size(nut):
    cap = make_capture(nut, size=(40, 30))
    cap.SetSupersample(2)
    em = chain(cap, vtkGBufferEdgeMap())
    shift = vtkImageShiftScale()
    shift.SetInputConnection(em.GetOutputPort())
    shift.SetInputArrayToProcess(0, 0, 0, 0, "edge_map")
    shift.SetOutputScalarTypeToFloat()
    shift.Update()
    raise_pipeline_errors(shift)
    assert cap.GetOutput().GetDimensions() == (80, 60, 1)
    assert em.GetOutput().GetDimensions() == (40, 30, 1)
    assert shift.GetOutput().GetDimensions() == (40, 30, 1)
    g = sg.capture(nut, window_size=(40, 30), supersample=2)
    assert np.array_equal(image_array(em, "edge_map"), F.edge_map(g))


def test_vtk_renderer_scene():
    sphere = pv.Sphere(radius=1.0)
    mapper = vtkPolyDataMapper()
    mapper.SetInputData(sphere)
    actor = vtkActor()
    actor.SetMapper(mapper)
    actor.SetPosition(3.0, 0.0, 0.0)
    hidden = vtkActor()  # invisible actors are left out
    hidden_mapper = vtkPolyDataMapper()
    hidden_mapper.SetInputData(pv.Cube(center=(0, 0, 5)))
    hidden.SetMapper(hidden_mapper)
    hidden.SetVisibility(False)
    ren = vtkRenderer()
    ren.AddActor(actor)
    ren.AddActor(hidden)
    cam = ren.GetActiveCamera()
    cam.SetPosition(3.0, 0.0, 10.0)
    cam.SetFocalPoint(3.0, 0.0, 0.0)
    cap = make_capture(ren, size=(48, 32))
    cap.Update()
    g = sg.GBuffer.from_pyvista(pv.wrap(cap.GetOutput()))
    ref = sg.capture(sphere.translate((3.0, 0.0, 0.0)), window_size=(48, 32), camera=cam)
    assert np.array_equal(g.mask, ref.mask) and g.mask.any()
    np.testing.assert_allclose(g.world[g.mask], ref.world[ref.mask], atol=1e-6)
    # the actor's transform was applied: the sphere is centred on x = 3
    assert abs(np.nanmean(g.world[..., 0]) - 3.0) < 0.05


# ---------------------------------------------------------------------------- errors
def test_bad_parameters_raise_from_the_setter(nut):
    cap = vtkGBufferCapture()
    with pytest.raises(InputError, match="window_size"):
        cap.SetWindowSize(0, 10)
    with pytest.raises(InputError, match="supersample"):
        cap.SetSupersample(0)
    with pytest.raises(InputError, match="camera"):
        cap.SetCamera("nowhere")
    with pytest.raises(InputError, match="scene"):
        cap.SetScene([])
    with pytest.raises(InputError, match="feature_angle"):
        cap.SetFeatureAngle(200)
    em = vtkGBufferEdgeMap()
    with pytest.raises(InputError, match="width"):
        em.SetWidth(0.5)
    with pytest.raises(InputError, match="operator"):
        em.SetOperator("laplace")
    with pytest.raises(InputError, match="unknown parameter"):
        em.SetParameter("interval", 3)
    cl = vtkGBufferContourLines()
    with pytest.raises(InputError, match="interval"):
        cl.SetInterval(-1)
    with pytest.raises(InputError, match="component"):
        cl.SetInputComponent(-1)
    lam = vtkGBufferLambert()
    with pytest.raises(InputError, match="ambient"):
        lam.SetAmbient(2)
    # a refused value leaves the algorithm as it was, unmodified
    mtime = em.GetMTime()
    with pytest.raises(InputError):
        em.SetCreaseAngle(200)
    assert em.GetCreaseAngle() == 30.0 and em.GetMTime() == mtime


def test_errors_while_executing_surface(nut):
    cap = make_capture(nut, size=(48, 32))
    cl = chain(cap, vtkGBufferContourLines())
    cl.SetInputArrayName("no_such_array")
    cl.SetInterval(1)
    with pytest.raises(InputError, match="no_such_array"):
        cl.Update()
    assert isinstance(cl.last_error, InputError)
    assert cl.GetOutput().GetNumberOfPoints() == 0  # emptied, never stale

    # through a plain VTK filter downstream: raise_pipeline_errors finds it
    shift = vtkImageShiftScale()
    shift.SetInputConnection(cl.GetOutputPort())
    shift.Update()
    with pytest.raises(InputError, match="no_such_array"):
        raise_pipeline_errors(shift)

    cl.SetInputArrayName("depth")  # fixed: runs again, error cleared
    cl.Update()
    assert cl.last_error is None
    assert image_array(cl, "contour_lines").shape == (32, 48)

    # a capture without a scene, and a G-buffer filter on an image without a G-buffer
    empty = vtkGBufferCapture()
    with pytest.raises(InputError, match="no scene"):
        empty.Update()
    em = vtkGBufferEdgeMap()
    em.SetInputData(pv.ImageData(dimensions=(4, 4, 1)))
    with pytest.raises(InputError, match="not a sciviz_gbuf G-buffer"):
        em.Update()
    # the error of the most upstream failing algorithm is the one raised
    down = chain(empty, vtkGBufferSobelGradient())
    with pytest.raises(InputError, match="no scene"):
        down.Update()


BAD_VALUES = {
    "contour_lines": ("interval", -1.0),
    "hatching": ("spacing", -1.0),
    "hillshade": ("altitude", 100.0),
    "color_bands": ("interval", -1.0),
    "lambert": ("ambient", 2.0),
    "profile_edges": ("width", 0.5),
    "internal_edges": ("crease_angle", 200.0),
    "crease_edges": ("depth_jump", -1.0),
    "id_edges": ("ids", "face"),
    "edge_map": ("operator", "laplace"),
    "reflection_lines": ("style", "dots"),
    "isophotes": ("interval", -5.0),
}


@pytest.mark.parametrize("name", sorted(BAD_VALUES))
def test_every_filter_validates_in_its_setter(name):
    alg = ALGORITHMS[name]()
    pname, bad = BAD_VALUES[name]
    mtime = alg.GetMTime()
    with pytest.raises(InputError, match=pname):
        getattr(alg, "Set" + "".join(p.capitalize() for p in pname.split("_")))(bad)
    assert alg.GetMTime() == mtime and alg.GetParameters() == {}
    # setting a parameter to its default when unset is no change either
    default = alg.GetParameter(pname)
    if default is not None:
        alg.SetParameter(pname, default)
        assert alg.GetMTime() == mtime


def test_plotter_scene_uses_its_window_size_and_camera():
    sphere = pv.Sphere()
    pl = pv.Plotter(off_screen=True, window_size=(48, 32))
    pl.add_mesh(sphere)
    pl.camera_position = "xz"
    cap = vtkGBufferCapture()
    cap.SetScene(pl)
    em = chain(cap, vtkGBufferProfileEdges())
    em.Update()
    ref = sg.capture(pl)
    assert em.GetOutput().GetDimensions() == (48, 32, 1)
    assert np.array_equal(image_array(em, "profile_edges"), F.profile_edges(ref))
    pl.close()


@pytest.mark.parametrize("feed", ["set_input_data", "through_plain_vtk"])
def test_supersampled_gbuffer_from_data_or_through_plain_vtk(nut, feed):
    g = sg.capture(nut, window_size=(40, 30), supersample=2)
    em = vtkGBufferEdgeMap()
    if feed == "set_input_data":  # e.g. a G-buffer loaded from a .vti file
        em.SetInputData(g.to_pyvista())
    else:
        # keep a reference: an output port does not keep its algorithm alive (plain VTK too)
        cap = make_capture(nut, size=(40, 30))
        cap.SetSupersample(2)
        passthrough = vtkImageChangeInformation()  # a plain VTK filter that keeps the image
        passthrough.SetInputConnection(cap.GetOutputPort())
        em.SetInputConnection(passthrough.GetOutputPort())
    shift = vtkImageShiftScale()  # needs the right extent announced before execution
    shift.SetInputConnection(em.GetOutputPort())
    shift.SetOutputScalarTypeToFloat()
    shift.Update()
    raise_pipeline_errors(shift)
    assert shift.GetOutput().GetDimensions() == (40, 30, 1)
    assert np.array_equal(image_array(em, "edge_map"), F.edge_map(g))
