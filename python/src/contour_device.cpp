// keymesh.contour on a tensor of another library (DLPack, or
// __cuda_array_interface__): a host tensor becomes a numpy array over the
// same memory (host_view, then the numpy path: the same call, the same
// mesh); a CUDA tensor is contoured where it lies (cuda::contour_device) and
// the mesh handed back as keymesh.DeviceArrays, which python/keymesh/
// _foreign.py turns into the input's library. No host copy either way.
#include <chrono>

#include "foreign_tensor.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/cuda/backend.hpp"
#include "keymesh/cuda/device_contour.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/report_fields.hpp"

namespace keymesh::python {

namespace {

const VolumeUse kContourUse{"contour", 2, "volume must be a 3-D array, a DLPack tensor or a keymesh.Volume"};

// The tensor of a "dltensor" capsule or of an object with __cuda_array_interface__.
ForeignTensor tensor_of(const py::object& source) {
  if (py::isinstance<py::capsule>(source)) return tensor_from_dlpack(source.cast<py::capsule>());
  if (py::hasattr(source, "__cuda_array_interface__")) return tensor_from_cuda_array_interface(source);
  throw py::type_error("contour_device: expected a DLPack capsule or an object with __cuda_array_interface__");
}

// The device volume over a CUDA tensor's samples, checked as a numpy volume
// is (ndim, dtype, samples per axis, geometry), and C- or Fortran-contiguous:
// a C-ordered tensor is read as the grid with the axes reversed, mirrored
// back on the device, as contour does with a C-ordered numpy array.
cuda::DeviceVolume device_volume(const ForeignTensor& t, const py::object& spacing, const py::object& origin) {
  if (t.shape.size() != 3)
    throw py::value_error("volume must be 3-D (axis 0 = x), got ndim=" + std::to_string(t.shape.size()));
  if (!t.dtype.attr("isnative").cast<bool>())
    throw py::type_error("volume has dtype " + dtype_name(t.dtype) +
                         " (another byte order): a CUDA volume is read in native order");
  cuda::DeviceVolume v;
  v.grid.type = scalar_type_of(t.dtype, "volume");
  check_volume_shape(t.shape, kContourUse);
  const std::array<double, 3> s = spacing.is_none() ? std::array<double, 3>{1, 1, 1} : triple(spacing, "spacing");
  const std::array<double, 3> o = origin.is_none() ? std::array<double, 3>{0, 0, 0} : triple(origin, "origin");
  check_float32_geometry({t.shape[0], t.shape[1], t.shape[2]}, o, s, "contour");
  const bool fortran = t.contiguous(true);
  if (!fortran && !t.contiguous(false))
    throw py::value_error("contour: a CUDA volume must be C- or Fortran-contiguous, got shape " + shape_text(t.shape) +
                          " with strides " + shape_text(t.strides) +
                          " bytes; make it contiguous on the device first (cupy.ascontiguousarray(v), v.contiguous())");
  v.mirror_back = !fortran;
  for (int a = 0; a < 3; ++a) {
    const int from = v.mirror_back ? 2 - a : a;
    v.grid.dims[a] = t.shape[static_cast<std::size_t>(from)];
    v.grid.spacing[a] = s[static_cast<std::size_t>(from)];
    v.grid.origin[a] = o[static_cast<std::size_t>(from)];
  }
  v.samples = t.data;
  v.device = t.device_id;
  v.ready_after = t.ready_after;
  return v;
}

// A device mesh as contour's (points, cells, None, point_data, {}), of keymesh.DeviceArrays.
py::tuple device_mesh_to_python(cuda::DeviceMesh&& m) {
  const py::dtype f4("float32"), u4("uint32");
  auto array = [&m](std::shared_ptr<void> buffer, const py::dtype& dtype, std::vector<py::ssize_t> shape) {
    void* data = buffer.get();
    return device_array(std::move(buffer), data, static_cast<int>(TensorDevice::Cuda), m.device, dtype,
                        std::move(shape));
  };
  py::dict point_data;
  for (cuda::DeviceField& f : m.point_fields)
    point_data[py::str(f.name)] =
        f.components == 1 ? array(std::move(f.values), f4, {m.points}) : array(std::move(f.values), f4, {m.points, 3});
  py::object points = array(std::move(m.xyz), f4, {m.points, 3});
  py::object cells = array(std::move(m.connectivity), u4, {m.triangles, 3});
  return py::make_tuple(points, cells, py::none(), point_data, py::dict());
}

py::tuple contour_device(const py::object& source, const std::vector<double>& isovalues, const py::object& spacing,
                         const py::object& origin, const std::string& normals, const std::string& weld, bool coarsen,
                         bool curvature, const py::object& callback, bool scalars) {
  const PythonProgress progress(callback);
  generate::ContourOptions opt = contour_options(isovalues, normals, weld, coarsen, curvature, scalars, "cuda");
  const ForeignTensor tensor = tensor_of(source);  // its owner keeps the samples until this returns
  if (!tensor.on_cuda()) throw py::value_error("contour_device: the tensor is not in CUDA device memory");
  const cuda::DeviceVolume volume = device_volume(tensor, spacing, origin);
  opt.reversed_axes = volume.mirror_back;
  generate::ContourStats stats;
  const auto t0 = std::chrono::steady_clock::now();
  cuda::DeviceMesh mesh = run_released(0, progress, [&] {
    progress::report("contour", 0.0);
    try {
      cuda::DeviceMesh m = cuda::contour_device(volume, opt, &stats);
      progress::report("contour", 1.0);
      return m;
    } catch (const std::exception&) {
      rethrow_in_python_words();
    }
  });
  py::dict info;
  info["copy"] = 0.0;
  info["contour"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  info["mirror"] = 0.0;  // on the device, within the contour
  generate::visit_stage_seconds(stats, into(info));
  info["key_bits"] = stats.key_bits;
  info["device_peak_bytes"] = stats.device_peak_bytes;
  info["zero_copy"] = true;
  info["backend"] = "cuda";
  return py::make_tuple(device_mesh_to_python(std::move(mesh)), info);
}

// The CLI's option names in a library message said as Python says them.
std::string in_python_words(std::string message) {
  using Words = std::pair<std::string, std::string>;
  for (const auto& [cli, python] :
       {Words{"--backend cuda", "backend='cuda'"}, Words{"--backend cpu", "backend='cpu'"},
        Words{"(--weld vertexweld)", "(weld='vertexweld')"}, Words{"(--coarsen)", "(coarsen=True)"}})
    for (auto at = message.find(cli); at != std::string::npos; at = message.find(cli, at + python.size()))
      message.replace(at, cli.size(), python);
  return message;
}

}  // namespace

void rethrow_in_python_words() {
  try {
    throw;
  } catch (const LimitError& e) {
    throw LimitError(in_python_words(e.what()));
  } catch (const InputError& e) {
    throw InputError(in_python_words(e.what()));
  }
}

void register_contour_device(py::module_& m) {
  m.def("contour_device", &contour_device, py::arg("source"), py::arg("isovalues"), py::arg("spacing") = py::none(),
        py::arg("origin") = py::none(), py::arg("normals") = "average", py::arg("weld") = "keyreduce",
        py::arg("coarsen") = false, py::arg("curvature") = false, py::arg("progress") = py::none(),
        py::arg("scalars") = true,
        "Marching cubes on a CUDA tensor (a 'dltensor' capsule or an object with __cuda_array_interface__), the mesh "
        "left on the device as keymesh.DeviceArrays. Use keymesh.contour.");
  m.def("host_view", [](const py::capsule& capsule) {
    ForeignTensor t = tensor_from_dlpack(capsule);
    if (t.on_cuda()) throw py::value_error("host_view: the tensor is in CUDA device memory");
    return host_array_of(std::move(t));
  }, py::arg("capsule"), "A numpy array over a host DLPack tensor's memory (no copy); the capsule is consumed.");
  m.def("cuda_available", [] {
    std::string why;
    return cuda::available(&why) ? py::object(py::none()) : py::object(py::str(why));
  }, "None when backend='cuda' can run here, else why not.");
  register_device_array(m);
}

}  // namespace keymesh::python
