"""Hostile inputs to the Python module (issue 34): the interpreter survives
every one with a clear exception.

- Copies that cannot be allocated (strided and zero-stride arrays) raise
  MemoryError naming the array and its size; these run in a child process
  with 2 GiB of address space, so that a crash is a failed test, not a dead
  pytest.
- Spacing and origin are checked as the volume readers check a file's
  (check_float32_geometry): nothing past float32, nothing NaN.
- Messages name the real cause: axes as the docs name them (axis 0 = x),
  spacing/origin rather than the points, a NUL byte in a path, a VTK array
  numpy cannot view, an integer past 64 bits.
"""
import math
import os
import resource
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import keymesh

GIB = 2 ** 30
# A sanitizer reserves terabytes of shadow memory (no RLIMIT_AS under one),
# and its allocator aborts on the huge requests these cases make.
SANITIZED = any(k in os.environ for k in ("ASAN_OPTIONS", "TSAN_OPTIONS", "UBSAN_OPTIONS"))
address_space_limited = pytest.mark.skipif(SANITIZED, reason="no RLIMIT_AS under a sanitizer")
SMALL = np.random.default_rng(1).random((6, 7, 8)).astype(np.float32)
LABELS = (SMALL > 0.5).astype(np.uint8)


# -- allocations: a child process with 2 GiB of address space ------------

def run_limited(code, address_space=2 * GIB, timeout=120):
    """Runs `code` in a fresh interpreter limited to `address_space` bytes;
    returns (exit status, the last line it printed). The code prints the
    exception it got as 'ClassName: message' (or 'returned')."""
    body = textwrap.indent(textwrap.dedent(code), "    ")
    script = ("import numpy as np, keymesh\n"
              "from numpy.lib.stride_tricks import as_strided\n"
              "try:\n" + body + "\n"
              "except BaseException as e:\n"
              "    print(f'{type(e).__name__}: {e}', flush=True)\n"
              "else:\n"
              "    print('returned', flush=True)\n")

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (address_space, address_space))

    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=timeout,
                       preexec_fn=limit, env=dict(os.environ, OMP_NUM_THREADS="2"))
    lines = r.stdout.strip().splitlines()
    return r.returncode, (lines[-1] if lines else r.stderr.strip()[-500:])


def assert_memory_error(code, *named):
    rc, last = run_limited(code)
    assert rc == 0, f"the interpreter died (status {rc}): {last}"
    assert last.startswith("MemoryError") or last.startswith("_ArrayMemoryError"), last
    for word in named:
        assert word in last, last


@address_space_limited
def test_strided_volume_copy_past_the_address_space():
    # 1.28 GiB of samples, reversed: the C-ordered copy does not fit in 2 GiB
    assert_memory_error("keymesh.contour(np.zeros((700, 700, 700), 'f4')[::-1], .5)", "volume", "GiB")


@address_space_limited
def test_strided_label_map_copy_past_the_address_space():
    assert_memory_error("keymesh.contour_labels(np.zeros((1100, 1100, 1100), 'u1')[::-1])", "volume", "GiB")


@address_space_limited
@pytest.mark.parametrize("dtype,call", [
    ("float32", "keymesh.contour(v, .5)"), ("float32", "keymesh.tetrahedralize(v)"),
    ("uint8", "keymesh.contour_labels(v)")])
@pytest.mark.parametrize("log2", [33, 60])
def test_zero_stride_volume_claiming_2_to_the_n_samples(dtype, call, log2):
    # numpy itself refuses a view of more than 2^63 bytes
    log2 += 2 if dtype == "uint8" and log2 == 60 else 0
    a, b = log2 // 3, log2 - 2 * (log2 // 3)
    assert_memory_error(f"v = np.broadcast_to(np.{dtype}(0), (2 ** {a}, 2 ** {a}, 2 ** {b}))\n{call}", "volume")


@address_space_limited
def test_zero_stride_keys_past_the_index_map_are_a_limit_error():
    rc, last = run_limited("""
        n = 2 ** 32 + 1
        keymesh.key_reduce(np.broadcast_to(np.uint32(1), (n,)), np.broadcast_to(np.float32(1), (n,)))""")
    assert rc == 0, last
    assert last.startswith("LimitError") and "4294967297" in last, last


@address_space_limited
def test_zero_stride_keys_whose_copy_does_not_fit():
    assert_memory_error("""
        n = 2 ** 31
        keymesh.key_reduce(np.broadcast_to(np.uint64(1), (n,)), np.broadcast_to(np.float32(1), (n,)))""", "keys")


@address_space_limited
def test_zero_stride_cells_of_subdivide():
    assert_memory_error("""
        cells = np.broadcast_to(np.array([0, 1, 2], np.int64), (2 ** 40, 3))
        keymesh.subdivide(keymesh.Mesh(np.eye(3, dtype=np.float32), cells))""", "mesh.cells")


@address_space_limited
def test_zero_stride_points_and_fields():
    assert_memory_error("""
        points = np.broadcast_to(np.float64(0), (2 ** 40, 3))
        keymesh.check(keymesh.Mesh(points, np.zeros((0, 3), np.int64)))""", "mesh.points")
    assert_memory_error("""
        m = keymesh.Mesh(np.eye(3, dtype=np.float32), np.array([[0, 1, 2]]))
        m.cell_data["big"] = np.broadcast_to(np.float64(0), (1, 2 ** 40))
        keymesh.check(m)""", "mesh.cell_data['big']")
    # 2^62 bytes of uint8 as float32: past the address space, refused before numpy is asked
    assert_memory_error("""
        points = np.broadcast_to(np.uint8(0), (2 ** 61, 3))
        keymesh.check(keymesh.Mesh(points, np.zeros((0, 3), np.int64)))""", "mesh.points", "would pass the address space")


@address_space_limited
def test_volume_zeros_past_the_address_space():
    assert_memory_error("keymesh.Volume.zeros((2048, 2048, 2048), 'float32')", "Volume", "32 GiB")


def test_a_copy_that_fits_still_contours():
    flipped = keymesh.contour(SMALL[::-1], 0.5)
    copied = keymesh.contour(np.ascontiguousarray(SMALL[::-1]), 0.5)
    assert np.array_equal(flipped.points, copied.points) and np.array_equal(flipped.cells, copied.cells)
    broadcast = keymesh.contour(np.broadcast_to(SMALL[:, :, :1], SMALL.shape), 0.5)
    assert broadcast.n_cells == keymesh.contour(np.repeat(SMALL[:, :, :1], 8, axis=2), 0.5).n_cells


# -- spacing and origin: the volume readers' check ------------------------

BAD_GEOMETRY = [
    (dict(spacing=(1e39, 1, 1)), r"spacing x = 1e\+39 is not a finite float32"),
    (dict(spacing=(1, math.nan, 1)), r"spacing y = nan is not a finite float32"),
    (dict(spacing=(1, 1, math.inf)), r"spacing z = inf is not a finite float32"),
    (dict(origin=(1e39, 0, 0)), r"origin x = 1e\+39 is not a finite float32"),
    (dict(origin=(0, -math.inf, 0)), r"origin y = -inf is not a finite float32"),
    (dict(origin=(3e38, 0, 0), spacing=(1e37, 1, 1)), r"point 5 along x lies at 3\.5e\+38"),
]


@pytest.mark.parametrize("geometry,message", BAD_GEOMETRY)
@pytest.mark.parametrize("order", ["C", "F"])
def test_contour_refuses_geometry_past_float32(geometry, message, order):
    # axes named as the docs name them (axis 0 = x) for C order too
    volume = np.asarray(SMALL[:6, :6, :6], order=order)
    with pytest.raises(keymesh.Error, match="contour: " + message):
        keymesh.contour(volume, 0.5, **geometry)


@pytest.mark.parametrize("geometry,message", BAD_GEOMETRY)
def test_tetrahedralize_and_labels_refuse_geometry_past_float32(geometry, message):
    with pytest.raises(keymesh.Error, match="tetrahedralize: " + message):
        keymesh.tetrahedralize(SMALL[:6, :6, :6], **geometry)
    with pytest.raises(keymesh.Error, match="contour_labels: " + message):
        keymesh.contour_labels(LABELS[:6, :6, :6], **geometry)


@pytest.mark.parametrize("geometry,message", BAD_GEOMETRY)
def test_volume_refuses_geometry_past_float32(geometry, message, tmp_path):
    with pytest.raises(keymesh.Error, match=message):
        keymesh.Volume(SMALL[:6, :6, :6], **geometry)
    with pytest.raises(keymesh.Error, match=message):
        keymesh.Volume.zeros((6, 6, 6), **geometry)
    with pytest.raises(keymesh.Error, match=message):
        keymesh.write(SMALL[:6, :6, :6], tmp_path / "v.vti", **geometry)
    assert not os.listdir(tmp_path)


def test_volume_spacing_set_after_creation_is_checked():
    v = keymesh.Volume(SMALL)
    with pytest.raises(keymesh.Error, match=r"Volume.spacing: spacing x = nan"):
        v.spacing = (math.nan, 1, 1)
    with pytest.raises(keymesh.Error, match=r"Volume.origin: origin y = inf"):
        v.origin = (0, math.inf, 0)
    v.spacing = (1e37, 1, 1)
    with pytest.raises(keymesh.Error, match=r"Volume.origin: point 5 along x"):
        v.origin = (3e38, 0, 0)
    # the refused values were not kept: the volume still contours
    assert v.spacing == (1e37, 1, 1) and v.origin == (0, 0, 0)
    assert np.isfinite(keymesh.contour(v, 0.5).points).all()


def test_volume_from_vtk_with_nan_spacing():
    pytest.importorskip("vtkmodules")
    image = keymesh.Volume(SMALL).to_vtk()
    image.SetSpacing(math.nan, 1, 1)
    with pytest.raises(keymesh.Error, match="spacing x = nan"):
        keymesh.from_vtk(image)


def test_coarsen_names_spacing_and_origin_not_the_points():
    mesh = keymesh.contour(SMALL, 0.5)
    with pytest.raises(keymesh.Error, match=r"coarsen: origin x = nan is not a finite float32"):
        keymesh.coarsen(mesh, origin=(math.nan, 0, 0))
    with pytest.raises(keymesh.Error, match=r"coarsen: spacing y = 1e\+39"):
        keymesh.coarsen(mesh, spacing=(1, 1e39, 1))
    with pytest.raises(keymesh.Error, match=r"spacings from the origin.*spacing is too fine") as e:
        keymesh.coarsen(mesh, spacing=(1e-300,) * 3)
    assert "not finite" not in str(e.value)
    with pytest.raises(keymesh.Error, match=r"origin too far"):
        keymesh.coarsen(mesh, origin=(3e38, 0, 0), spacing=(1e-20, 1, 1))


# -- messages ---------------------------------------------------------------

@pytest.mark.parametrize("shape,axis", [((0, 4, 4), "0 (x)"), ((1, 4, 4), "0 (x)"), ((4, 1, 4), "1 (y)"),
                                        ((4, 4, 1), "2 (z)")])
@pytest.mark.parametrize("order", ["C", "F"])
def test_too_few_samples_name_the_axis_as_the_docs_do(shape, axis, order):
    volume = np.zeros(shape, np.float32, order=order)
    with pytest.raises(keymesh.Error, match=r"contour: volume has shape .* along axis " + axis.replace("(", r"\(")
                       .replace(")", r"\)") + ", need at least 2"):
        keymesh.contour(volume, 0.5)
    with pytest.raises(keymesh.Error, match=r"tetrahedralize: .* along axis " + axis[0]):
        keymesh.tetrahedralize(volume)
    if shape[0] == 0:
        with pytest.raises(keymesh.Error, match=r"contour_labels: .* along axis 0 \(x\), need at least 1"):
            keymesh.contour_labels(volume.astype(np.uint8))


def test_nul_in_a_path_is_refused_by_name(tmp_path):
    path = str(tmp_path / "v.vti")
    keymesh.write(keymesh.Volume(SMALL), path)
    with pytest.raises(ValueError, match=r"read: the path .*v\.vti\\0junk' holds a NUL byte"):
        keymesh.read(path + "\0junk")
    mesh = keymesh.contour(SMALL, 0.5)
    target = str(tmp_path / "x.ply")
    for obj, name in [(mesh, target + "\0.vtp"), (keymesh.tetrahedralize(SMALL), target + "\0.vtu"),
                      (keymesh.Volume(SMALL), target + "\0.vti")]:
        with pytest.raises(ValueError, match="write: the path .* holds a NUL byte"):
            keymesh.write(obj, name)
    assert sorted(os.listdir(tmp_path)) == ["v.vti"]


def test_from_vtk_bit_arrays_raise_keymesh_error():
    pytest.importorskip("vtkmodules")
    from vtkmodules.vtkCommonCore import vtkBitArray
    from vtkmodules.vtkCommonDataModel import vtkImageData

    bits = vtkBitArray()
    bits.SetName("mask")
    bits.SetNumberOfTuples(27)
    image = vtkImageData()
    image.SetDimensions(3, 3, 3)
    image.GetPointData().SetScalars(bits)
    with pytest.raises(keymesh.Error, match="point scalars is a vtkBitArray"):
        keymesh.from_vtk(image)
    poly = keymesh.contour(SMALL, 0.5).to_vtk()
    field = vtkBitArray()
    field.SetName("flags")
    field.SetNumberOfTuples(poly.GetNumberOfPoints())
    poly.GetPointData().AddArray(field)
    with pytest.raises(keymesh.Error, match="point data array 'flags' is a vtkBitArray"):
        keymesh.from_vtk(poly)


BIG = 2 ** 70


@pytest.mark.parametrize("call,name", [
    (lambda: keymesh.contour(SMALL, 0.5, threads=BIG), "threads"),
    (lambda: keymesh.key_reduce(np.arange(3), np.ones(3), threads=2 ** 40), "threads"),
    (lambda: keymesh.check(keymesh.contour(SMALL, 0.5), threads=BIG), "threads"),
    (lambda: keymesh.tetrahedralize(SMALL, scheme=BIG), "scheme"),
    (lambda: keymesh.subdivide(keymesh.contour(SMALL, 0.5), levels=-BIG), "levels"),
    (lambda: keymesh.contour_labels(LABELS, background=2 ** 64), "background"),
    (lambda: keymesh.contour_labels(LABELS, labels=[1, 2 ** 64]), r"labels\[1\]"),
    (lambda: keymesh.contour_labels(LABELS, smoothing_iterations=2 ** 40), "smoothing_iterations"),
    (lambda: keymesh.contour_labels(LABELS, threads=BIG), "threads"),
    (lambda: keymesh.read("v.raw", dims=(2 ** 64, 1, 1), dtype="f4"), r"dims\[0\]"),
    (lambda: keymesh.read("v.raw", dims=(2, 2, 2), dtype="f4", header_bytes=2 ** 64), "header_bytes"),
    (lambda: keymesh.Volume.zeros((2, 2 ** 100, 2)), r"Volume shape\[1\]"),
    (lambda: keymesh.marching_cubes(SMALL, 0.5, step_size=BIG), "step_size"),
    (lambda: keymesh.contour(SMALL, 2 ** 2000), "iso"),
])
def test_integers_past_64_bits_name_the_argument(call, name):
    with pytest.raises(OverflowError, match=name):
        call()


def test_grid_cell_type_past_a_byte_names_it(tmp_path):
    grid = keymesh.tetrahedralize(SMALL)
    grid.cell_type = BIG
    with pytest.raises(ValueError, match="grid.cell_type must be a VTK cell type code"):
        keymesh.write(grid, tmp_path / "g.vtu")
