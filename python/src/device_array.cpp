// keymesh.DeviceArray: an array of a mesh made on the GPU (backend='cuda' on
// a CUDA tensor), in device memory, handed to Python without a copy. It
// exports itself both ways other libraries import device memory:
// __dlpack__ / __dlpack_device__ (cupy.from_dlpack, torch.from_dlpack,
// jax.dlpack.from_dlpack) and __cuda_array_interface__ (Numba, CuPy).
// keymesh.contour converts it into the input's library where that library
// has from_dlpack (python/keymesh/_foreign.py).
#include <dlpack/dlpack.h>

#include <cstdint>
#include <string>

#include "foreign_tensor.hpp"

namespace keymesh::python {

namespace {

struct DeviceArray {
  std::shared_ptr<void> buffer;  // the memory; freed when the last copy (exports included) goes
  void* data = nullptr;
  DLDevice device{kDLCUDA, 0};
  py::dtype dtype;
  std::vector<py::ssize_t> shape;  // C-contiguous
};

DLDataType dlpack_type_of(const py::dtype& dtype) {
  const char kind = dtype.kind();
  const auto code = kind == 'f' ? kDLFloat : (kind == 'u' ? kDLUInt : kDLInt);
  return DLDataType{static_cast<std::uint8_t>(code), static_cast<std::uint8_t>(8 * dtype.itemsize()), 1};
}

// One export: the DLPack struct, its shape, and a copy of the buffer's
// owner. No Python object inside: the consumer may call the deleter from
// any thread, without the GIL.
struct Export {
  DLManagedTensor managed{};
  std::vector<std::int64_t> shape, strides;  // strides in elements, C order (given: DLPack 1.2 wants them)
  std::shared_ptr<void> keep;
};

// A "dltensor" capsule nobody consumed runs the deleter itself.
void unused_capsule_destructor(PyObject* capsule) {
  if (!PyCapsule_IsValid(capsule, "dltensor")) return;  // consumed: renamed "used_dltensor"
  auto* m = static_cast<DLManagedTensor*>(PyCapsule_GetPointer(capsule, "dltensor"));
  if (m && m->deleter) m->deleter(m);
}

// __dlpack__(stream=None, max_version=None, dl_device=None, copy=None): a
// legacy (unversioned) capsule, which every consumer reads. The mesh is
// complete when keymesh returns it (its stream was synchronized), so no
// stream needs to wait. copy=True and another device are refused.
py::capsule to_dlpack(const DeviceArray& a, const py::object& /*stream*/, const py::object& /*max_version*/,
                      const py::object& dl_device, const py::object& copy) {
  if (!copy.is_none() && copy.cast<bool>())
    throw py::buffer_error("keymesh.DeviceArray.__dlpack__: copy=True is not supported (keymesh never copies here)");
  if (!dl_device.is_none()) {
    const auto d = dl_device.cast<std::pair<int, int>>();
    if (d.first != static_cast<int>(a.device.device_type) || d.second != a.device.device_id)
      throw py::buffer_error("keymesh.DeviceArray.__dlpack__: the array is on device (" +
                             std::to_string(a.device.device_type) + ", " + std::to_string(a.device.device_id) +
                             "), not the one asked for");
  }
  auto* e = new Export;
  e->shape.assign(a.shape.begin(), a.shape.end());
  e->strides.resize(e->shape.size());
  std::int64_t stride = 1;
  for (std::size_t d = e->shape.size(); d-- > 0;) e->strides[d] = stride, stride *= e->shape[d];
  e->keep = a.buffer;
  e->managed.dl_tensor = DLTensor{a.data, a.device, static_cast<int>(e->shape.size()), dlpack_type_of(a.dtype),
                                  e->shape.data(), e->strides.data(), 0};
  e->managed.manager_ctx = e;
  e->managed.deleter = [](DLManagedTensor* m) { delete static_cast<Export*>(m->manager_ctx); };
  PyObject* capsule = PyCapsule_New(&e->managed, "dltensor", unused_capsule_destructor);
  if (!capsule) {
    delete e;
    throw py::error_already_set();
  }
  return py::reinterpret_steal<py::capsule>(capsule);
}

// __cuda_array_interface__ (version 3): AttributeError for host memory, so
// that hasattr() tells a consumer which protocol applies.
py::dict cuda_array_interface(const DeviceArray& a) {
  if (a.device.device_type != kDLCUDA)
    throw py::attribute_error("keymesh.DeviceArray: host memory has no __cuda_array_interface__");
  py::dict d;
  d["shape"] = py::tuple(py::cast(a.shape));
  d["typestr"] = a.dtype.attr("str");
  d["data"] = py::make_tuple(reinterpret_cast<std::uintptr_t>(a.data), false);
  d["strides"] = py::none();
  d["stream"] = py::none();  // complete: nothing to wait for
  d["version"] = 3;
  return d;
}

}  // namespace

py::object device_array(std::shared_ptr<void> buffer, void* data, int device_type, int device_id,
                        const py::dtype& dtype, std::vector<py::ssize_t> shape) {
  DeviceArray a{std::move(buffer), data, DLDevice{static_cast<DLDeviceType>(device_type), device_id}, dtype,
                std::move(shape)};
  return py::cast(std::move(a));
}

void register_device_array(py::module_& m) {
  py::class_<DeviceArray>(m, "DeviceArray",
                          "A mesh array in device memory (backend='cuda'), exported without a copy through DLPack "
                          "(__dlpack__, __dlpack_device__) and __cuda_array_interface__.")
      .def_property_readonly("shape", [](const DeviceArray& a) { return py::tuple(py::cast(a.shape)); })
      .def_property_readonly("dtype", [](const DeviceArray& a) { return a.dtype; })
      .def_property_readonly("__cuda_array_interface__", &cuda_array_interface)
      .def("__dlpack_device__",
           [](const DeviceArray& a) {
             return py::make_tuple(static_cast<int>(a.device.device_type), a.device.device_id);
           })
      .def("__dlpack__", &to_dlpack, py::kw_only(), py::arg("stream") = py::none(),
           py::arg("max_version") = py::none(), py::arg("dl_device") = py::none(), py::arg("copy") = py::none())
      .def("__len__", [](const DeviceArray& a) { return a.shape.empty() ? 0 : a.shape[0]; })
      .def("view", [](const DeviceArray& a, const py::object& dtype) {
        // The same bytes as another type of the same size (uint32 ids as int32), as numpy's view.
        const py::dtype to = py::dtype::from_args(dtype);
        if (to.itemsize() != a.dtype.itemsize())
          throw py::value_error("keymesh.DeviceArray.view: " + dtype_name(to) + " is not the size of " +
                                dtype_name(a.dtype));
        return DeviceArray{a.buffer, a.data, a.device, to, a.shape};
      }, py::arg("dtype"))
      .def("__repr__", [](const DeviceArray& a) {
        return "keymesh.DeviceArray(shape=" + shape_text(a.shape) + ", dtype=" + dtype_name(a.dtype) +
               ", device=(" + std::to_string(a.device.device_type) + ", " + std::to_string(a.device.device_id) + "))";
      });
  // For the tests, where no GPU is: the exporter over a C-contiguous numpy
  // array's memory, said to lie on `device` (a CUDA one is never read here).
  m.def("_device_array_over", [](const py::array& host, int device_type, int device_id) {
    if (!(host.flags() & py::array::c_style)) throw py::value_error("a C-contiguous array is needed");
    auto* keep = new py::object(host);
    std::shared_ptr<void> buffer(keep, [](void* p) {
      py::gil_scoped_acquire gil;
      delete static_cast<py::object*>(p);
    });
    return device_array(std::move(buffer), const_cast<void*>(host.data()), device_type, device_id, host.dtype(),
                        std::vector<py::ssize_t>(host.shape(), host.shape() + host.ndim()));
  }, py::arg("host"), py::arg("device_type"), py::arg("device_id"));
}

}  // namespace keymesh::python
