"""keymesh.contour on tensors of other libraries: DLPack and
__cuda_array_interface__ in, arrays of the same library out (python/keymesh/
_foreign.py, python/src/foreign_tensor.cpp, device_array.cpp,
contour_device.cpp).

Without a GPU: host tensors give exactly the numpy call's mesh and are read
without a copy where contiguous; bad tensors and CUDA tensors are refused
with one clear error, the interpreter alive. The GPU tests at the end (CuPy
and PyTorch CUDA round trips) skip here, saying why; scripts/gpu_check.sh
runs them where a GPU and the module are.
"""
import gc
import tracemalloc
import weakref

import numpy as np
import pytest

import keymesh
from keymesh import _keymesh as _ext

from conftest import sphere_field

NO_GPU = keymesh.cuda_available()  # None where backend="cuda" runs


class DLPackOnly:
    """Exposes a numpy array through DLPack and nothing else (no buffer
    protocol, no __array__): keymesh must go through the capsule."""

    __slots__ = ("_array", "_device")

    def __init__(self, array, device=None):
        self._array = array
        self._device = device

    def __dlpack__(self, stream=None):
        return self._array.__dlpack__()

    def __dlpack_device__(self):
        return self._device or self._array.__dlpack_device__()


class CudaInterfaceOnly:
    """Exposes only a __cuda_array_interface__ dictionary."""

    def __init__(self, interface, keep=None):
        self.__cuda_array_interface__ = interface
        self._keep = keep


def field_of(dtype, shape=(21, 18, 23)):
    """A sphere's distance field in `dtype`, spanning its range for integers."""
    f = sphere_field(shape, center=(10.3, 8.9, 11.6))
    if np.issubdtype(dtype, np.integer):
        lo, hi = max(np.iinfo(dtype).min, -1000), min(np.iinfo(dtype).max, 1000)
        f = lo + (hi - lo) * f / f.max()
    return f.astype(dtype)


def iso_of(volume):
    return float(np.asarray(volume, np.float64).mean()) + 0.25


def assert_same_mesh(a, b):
    assert type(a.points) is np.ndarray and type(b.points) is np.ndarray
    np.testing.assert_array_equal(a.points, b.points)
    np.testing.assert_array_equal(a.cells, b.cells)
    assert sorted(a.point_data) == sorted(b.point_data)
    for name in a.point_data:
        assert a.point_data[name].tobytes() == b.point_data[name].tobytes(), name
    assert a.n_cells > 0


LAYOUTS = {
    "C": lambda v: v,
    "F": np.asfortranarray,
    "transposed": lambda v: v.transpose(2, 0, 1),
    "sliced": lambda v: v[::2, 1:, 1:-1],
}


@pytest.mark.parametrize("dtype", [np.uint8, np.int8, np.uint16, np.int16, np.int32, np.float32, np.float64])
@pytest.mark.parametrize("layout", sorted(LAYOUTS))
def test_dlpack_only_equals_numpy(dtype, layout):
    volume = LAYOUTS[layout](field_of(dtype))
    iso = iso_of(volume)
    for normals in ("average", "gradient", "none"):
        expected = keymesh.contour(volume, iso, normals=normals)
        got = keymesh.contour(DLPackOnly(volume), iso, normals=normals)
        assert_same_mesh(got, expected)


def test_dlpack_several_isovalues_spacing_origin():
    volume = field_of(np.float32)
    args = dict(spacing=(0.5, 1.25, 2.0), origin=(-3, 1, 7), normals="average")
    assert_same_mesh(keymesh.contour(DLPackOnly(volume), [4.5, 7.25], **args),
                     keymesh.contour(volume, [4.5, 7.25], **args))


def test_host_view_shares_memory_and_releases_the_producer():
    volume = field_of(np.float32)
    watch = weakref.ref(volume)
    view = _ext.host_view(volume.__dlpack__())
    assert view.__array_interface__["data"][0] == volume.__array_interface__["data"][0]
    assert view.strides == volume.strides and view.shape == volume.shape
    del volume
    gc.collect()
    assert watch() is not None, "the view must keep the producer alive"
    del view
    gc.collect()
    assert watch() is None, "the producer's deleter must run when the view goes"


def traced_peak(call):
    """The peak of the memory Python and numpy traced during call()."""
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        call()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_contiguous_tensor_is_read_without_a_copy():
    # numpy reports its data allocations to tracemalloc: a copy of the
    # volume would show in the peak. The mesh is the library's own memory
    # (not traced), the volume 8 MB, its sphere's mesh small.
    volume = sphere_field((128, 128, 64)).astype(np.float64)
    for layout in (lambda v: v, np.asfortranarray):
        v = layout(volume)
        peak = traced_peak(lambda: keymesh.contour(DLPackOnly(v), 30.5, normals="none", scalars=False))
        assert peak < v.nbytes / 4, (peak, v.nbytes)
    # The check sees a copy where there is one: a strided view is made contiguous.
    strided = volume[:, :, ::2]
    peak = traced_peak(lambda: keymesh.contour(DLPackOnly(strided), 30.5, normals="none", scalars=False))
    assert peak >= strided.size * strided.itemsize, (peak, strided.nbytes)


@pytest.mark.parametrize("volume, error, match", [
    (np.zeros((4, 4), np.float32), ValueError, "must be 3-D"),
    (np.zeros((2, 2, 2, 2), np.float32), ValueError, "must be 3-D"),
    (np.zeros((4, 4, 4), np.float16), TypeError, "float16"),
    (np.zeros((4, 4, 4), np.int64), TypeError, "int64"),
    (np.zeros((4, 4, 4), np.uint32), TypeError, "uint32"),
    (np.zeros((4, 4, 4), np.complex64), TypeError, "complex64"),
    (np.zeros((4, 4, 4), np.bool_), TypeError, "bool"),
    (np.zeros((0, 4, 4), np.float32), keymesh.Error, r"0 sample\(s\) along axis 0 \(x\)"),
    (np.zeros((4, 1, 4), np.float32), keymesh.Error, r"1 sample\(s\) along axis 1 \(y\)"),
])
def test_bad_host_tensors_are_refused_as_numpy_arrays_are(volume, error, match):
    try:
        wrapped = DLPackOnly(volume)
        wrapped.__dlpack__()
    except (BufferError, TypeError) as e:  # numpy itself cannot export it (bool before numpy 1.25)
        with pytest.raises((BufferError, TypeError)):
            keymesh.contour(DLPackOnly(volume), 0.5)
        return
    with pytest.raises(error, match=match):
        keymesh.contour(DLPackOnly(volume), 0.5)
    with pytest.raises(error, match=match):
        keymesh.contour(volume, 0.5)


def test_read_only_tensor():
    volume = field_of(np.float32)
    volume.flags.writeable = False
    try:
        capsule = volume.__dlpack__()
    except BufferError as e:  # numpy < 2 exports no read-only array: its own message
        assert "readonly" in str(e).replace("-", "")
        with pytest.raises(BufferError, match="readonly"):
            keymesh.contour(DLPackOnly(volume), 5.5)
    else:
        del capsule
        assert_same_mesh(keymesh.contour(DLPackOnly(volume), 5.5), keymesh.contour(volume, 5.5))
    assert keymesh.contour(volume, 5.5).n_cells > 0  # a read-only numpy array is read as it is


def test_used_capsule_and_unknown_device_are_refused():
    volume = field_of(np.float32)
    capsule = volume.__dlpack__()
    _ext.host_view(capsule)

    class SameCapsule(DLPackOnly):
        def __dlpack__(self, stream=None):
            return capsule

    with pytest.raises(TypeError, match="used_dltensor"):
        keymesh.contour(SameCapsule(volume), 5.5)
    with pytest.raises(TypeError, match=r"DLPack device type 4 \(OpenCL\)"):
        keymesh.contour(DLPackOnly(volume, device=(4, 0)), 5.5)


def test_backend_argument():
    volume = field_of(np.float32)
    with pytest.raises(ValueError, match="backend must be 'cpu', 'cuda' or None"):
        keymesh.contour(volume, 5.5, backend="gpu")
    with pytest.raises(TypeError, match="backend must be"):
        keymesh.contour(volume, 5.5, backend=1)
    assert_same_mesh(keymesh.contour(volume, 5.5, backend="cpu"), keymesh.contour(volume, 5.5))


@pytest.mark.skipif(NO_GPU is None, reason="a GPU is usable here: the refusal is not what happens")
def test_backend_cuda_without_gpu_raises_cleanly():
    volume = field_of(np.float32)
    for call in (lambda: keymesh.contour(volume, 5.5, backend="cuda"),
                 lambda: keymesh.contour(DLPackOnly(volume), 5.5, backend="cuda"),
                 lambda: keymesh.contour(volume, 5.5, backend="cuda", curvature=True)):  # the GPU has it
        with pytest.raises(keymesh.Error, match=r"^backend='cuda': ") as e:
            call()
        assert "--backend" not in str(e.value)
        assert NO_GPU in str(e.value)
    # Options the GPU has no path for are refused by name first, in any build.
    with pytest.raises(keymesh.Error, match="per-point history"):
        keymesh.contour(volume, 5.5, backend="cuda", history=True)
    assert keymesh.contour(volume, 5.5).n_cells > 0  # the interpreter goes on


# A CUDA tensor fabricated over host memory: keymesh must refuse it before
# any kernel reads it (no GPU: none usable; a GPU: not device memory).
CUDA_REFUSAL = (r"^backend='cuda': "
                r"(no usable CUDA device|no CUDA device|keymesh was built without|.*not in device memory)")


def test_cuda_dlpack_tensor_is_refused_cleanly():
    volume = np.ascontiguousarray(field_of(np.float32))
    fake = _ext._device_array_over(volume, 2, 0)
    assert fake.__dlpack_device__() == (2, 0)
    with pytest.raises(keymesh.Error, match=CUDA_REFUSAL):
        keymesh.contour(fake, 5.5)
    with pytest.raises(keymesh.Error, match=CUDA_REFUSAL):
        keymesh.contour(CudaInterfaceOnly(fake.__cuda_array_interface__, fake), 5.5)
    with pytest.raises(keymesh.Error, match=CUDA_REFUSAL):  # lists where the interface has tuples
        keymesh.contour(interface_of(volume, shape=list(volume.shape), strides=list(volume.strides)), 5.5)
    with pytest.raises(ValueError, match="backend='cpu' reads host memory"):
        keymesh.contour(fake, 5.5, backend="cpu")
    assert keymesh.contour(volume, 5.5).n_cells > 0


def interface_of(volume, **changes):
    d = dict(shape=volume.shape, typestr=volume.dtype.str, data=(volume.ctypes.data, False),
             strides=volume.strides, version=3, stream=None)
    d.update(changes)
    return CudaInterfaceOnly(d, volume)


@pytest.mark.parametrize("changes, error, match", [
    (dict(shape=(21, 18 * 23)), ValueError, "must be 3-D"),
    (dict(typestr="<f2"), TypeError, "float16"),
    (dict(typestr=">f4"), TypeError, "another byte order"),
    (dict(shape=(21, 0, 23)), keymesh.Error, r"0 sample\(s\) along axis 1 \(y\)"),
    (dict(strides=(4, 84 * 23, 84 * 2)), ValueError, "C- or Fortran-contiguous"),
    (dict(mask=object()), TypeError, "mask"),
])
def test_bad_cuda_tensors_are_refused_before_the_device(changes, error, match):
    volume = np.ascontiguousarray(field_of(np.float32))
    with pytest.raises(error, match=match):
        keymesh.contour(interface_of(volume, **changes), 5.5)


def test_device_array_exports_dlpack_without_a_copy():
    volume = np.arange(24, dtype=np.float32).reshape(8, 3)
    watch = weakref.ref(volume)
    exported = _ext._device_array_over(volume, 1, 0)
    assert exported.shape == (8, 3) and exported.dtype == np.float32 and len(exported) == 8
    assert not hasattr(exported, "__cuda_array_interface__")  # host memory
    back = np.from_dlpack(exported)
    assert back.__array_interface__["data"][0] == volume.__array_interface__["data"][0]
    np.testing.assert_array_equal(back, volume)
    with pytest.raises(BufferError, match="copy=True"):
        exported.__dlpack__(copy=True)
    exported.__dlpack__()  # an unused capsule frees its export itself
    del volume, exported, back
    gc.collect()
    assert watch() is None
    ids = _ext._device_array_over(np.array([[1, 2**32 - 1]], np.uint32), 1, 0)
    as_int32 = np.from_dlpack(ids.view(np.int32))
    assert as_int32.dtype == np.int32 and as_int32.tolist() == [[1, -1]]
    with pytest.raises(ValueError, match="not the size of"):
        ids.view(np.float64)
    on_gpu = _ext._device_array_over(np.zeros((5, 3), np.uint32), 2, 1)
    assert on_gpu.__dlpack_device__() == (2, 1)
    cai = on_gpu.__cuda_array_interface__
    assert cai["shape"] == (5, 3) and cai["typestr"] == "<u4" and cai["version"] == 3 and cai["stream"] is None


def test_torch_cpu_tensor_gives_torch_tensors():
    torch = pytest.importorskip("torch", reason="PyTorch is not installed (not a keymesh dependency)")
    volume = field_of(np.float32)
    tensor = torch.from_numpy(volume)
    for view in (tensor.permute(2, 0, 1), tensor[::2, 1:], tensor.to(torch.int16)):  # strided, another dtype
        got, want = keymesh.contour(view, 5.5), keymesh.contour(view.numpy(), 5.5)
        np.testing.assert_array_equal(got.points.numpy(), want.points)
        np.testing.assert_array_equal(got.cells.numpy(), want.cells)
        np.testing.assert_array_equal(got.point_data["Normals"].numpy(), want.point_data["Normals"])
    mesh = keymesh.contour(tensor, 5.5)
    expected = keymesh.contour(volume, 5.5)
    assert isinstance(mesh.points, torch.Tensor) and mesh.points.device.type == "cpu"
    assert mesh.cells.dtype == torch.int64  # PyTorch's index type: it has no (usable) uint32
    np.testing.assert_array_equal(mesh.points.numpy(), expected.points)
    np.testing.assert_array_equal(mesh.cells.numpy(), expected.cells)
    np.testing.assert_array_equal(mesh.point_data["Normals"].numpy(), expected.point_data["Normals"])
    # Ids past 2^31 - 1 stay what they are (an int32 view widened, masked).
    from keymesh import _foreign
    ids = np.array([[0, 2**31 - 1, 2**31], [7, 2**32 - 2, 2**32 - 1]], np.uint32)
    widened = _foreign._torch_ids(torch.from_dlpack)(ids)
    assert widened.dtype == torch.int64
    np.testing.assert_array_equal(widened.numpy(), ids.astype(np.int64))
    # keymesh.DeviceArray's export as PyTorch reads it (on the GPU, the mesh's arrays go this way).
    exported = torch.from_dlpack(_ext._device_array_over(expected.points, 1, 0))
    assert exported.stride() == (3, 1) and exported.data_ptr() == expected.points.ctypes.data
    np.testing.assert_array_equal(exported.numpy(), expected.points)


# ---- on a GPU (scripts/gpu_check.sh runs these where one is) ----------------

gpu = pytest.mark.skipif(NO_GPU is not None, reason=f"backend='cuda' cannot run here: {NO_GPU}")


def assert_device_mesh_equals(mesh, expected, to_numpy):
    np.testing.assert_array_equal(to_numpy(mesh.points), expected.points)
    np.testing.assert_array_equal(to_numpy(mesh.cells), expected.cells)
    assert sorted(mesh.point_data) == sorted(expected.point_data)
    for name, values in mesh.point_data.items():
        assert to_numpy(values).tobytes() == expected.point_data[name].tobytes(), name


@gpu
@pytest.mark.parametrize("order", ["C", "F"])
@pytest.mark.parametrize("normals", ["average", "gradient", "none"])
def test_cupy_round_trip(order, normals):
    cupy = pytest.importorskip("cupy", reason="CuPy is not installed")
    volume = np.asarray(field_of(np.float32), order=order)
    expected = keymesh.contour(volume, [5.5, 7.25], normals=normals)
    on_gpu = cupy.asarray(volume, order=order)
    mesh = keymesh.contour(on_gpu, [5.5, 7.25], normals=normals)
    assert isinstance(mesh.points, cupy.ndarray) and mesh.points.device.id == on_gpu.device.id
    assert_device_mesh_equals(mesh, expected, cupy.asnumpy)
    # __cuda_array_interface__ alone: keymesh.DeviceArrays, which CuPy reads.
    mesh = keymesh.contour(CudaInterfaceOnly(on_gpu.__cuda_array_interface__, on_gpu), [5.5, 7.25], normals=normals)
    assert isinstance(mesh.points, keymesh.DeviceArray)
    assert_device_mesh_equals(mesh, expected, lambda a: cupy.asnumpy(cupy.asarray(a)))
    # A host volume on the GPU: numpy out, the same bits.
    assert_same_mesh(keymesh.contour(volume, [5.5, 7.25], normals=normals, backend="cuda"), expected)


@gpu
def test_torch_cuda_round_trip():
    torch = pytest.importorskip("torch", reason="PyTorch is not installed")
    if not torch.cuda.is_available():
        pytest.skip("PyTorch has no CUDA here")
    volume = field_of(np.int16)
    expected = keymesh.contour(volume, 40.5)
    mesh = keymesh.contour(torch.from_numpy(volume).cuda(), 40.5)
    assert isinstance(mesh.points, torch.Tensor) and mesh.points.is_cuda and mesh.cells.dtype == torch.int64
    assert_device_mesh_equals(mesh, expected, lambda t: t.cpu().numpy())
    with pytest.raises(ValueError, match="C- or Fortran-contiguous"):
        keymesh.contour(torch.from_numpy(volume).cuda()[::2], 40.5)
