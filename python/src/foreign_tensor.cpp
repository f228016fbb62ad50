// Tensors of other array libraries read through DLPack or
// __cuda_array_interface__ (foreign_tensor.hpp): the layout and the owner,
// no copy.
#include "foreign_tensor.hpp"

#include <dlpack/dlpack.h>

#include <string>

namespace keymesh::python {

namespace {

// numpy's name of a DLPack element type: "f4", "u2", "?"...; TypeError for
// one numpy has none for (bfloat16, vectors of lanes).
py::dtype dtype_of_dlpack(const DLDataType& t) {
  const int bytes = t.bits / 8;
  char kind = 0;
  switch (t.code) {
    case kDLInt: kind = 'i'; break;
    case kDLUInt: kind = 'u'; break;
    case kDLFloat: kind = 'f'; break;
    case kDLComplex: kind = 'c'; break;
    case 6: kind = 'b'; break;  // kDLBool (DLPack 0.8; dlpack.h 0.6 lacks the name)
    default: break;
  }
  const std::string what = "volume has DLPack dtype (code " + std::to_string(t.code) + ", " +
                           std::to_string(t.bits) + " bits, " + std::to_string(t.lanes) + " lanes)";
  if (kind == 0 || t.lanes != 1 || t.bits % 8 != 0 || bytes == 0)
    throw py::type_error(what + ", which numpy has no name for; keymesh supports uint8, int8, uint16, int16, "
                                "int32, float32 and float64");
  return py::dtype(kind == 'b' ? std::string("?") : std::string(1, kind) + std::to_string(bytes));
}

}  // namespace

bool ForeignTensor::contiguous(bool fortran) const {
  py::ssize_t expected = dtype.itemsize();
  const auto n = static_cast<py::ssize_t>(shape.size());
  for (py::ssize_t k = 0; k < n; ++k) {
    const auto d = static_cast<std::size_t>(fortran ? k : n - 1 - k);
    if (shape[d] != 1 && strides[d] != expected) return false;
    expected *= shape[d];
  }
  return true;
}

ForeignTensor tensor_from_dlpack(const py::capsule& capsule) {
  if (!PyCapsule_IsValid(capsule.ptr(), "dltensor"))
    throw py::type_error("volume.__dlpack__() returned a capsule named '" +
                         std::string(capsule.name() ? capsule.name() : "") +
                         "', not an unused 'dltensor' (a capsule can be read once)");
  auto* managed = static_cast<DLManagedTensor*>(PyCapsule_GetPointer(capsule.ptr(), "dltensor"));
  ForeignTensor t;
  // Consumed from here on: the producer's deleter runs when `owner` goes.
  PyCapsule_SetName(capsule.ptr(), "used_dltensor");
  t.owner = std::shared_ptr<void>(managed, [](void* p) {
    auto* m = static_cast<DLManagedTensor*>(p);
    if (m->deleter) m->deleter(m);
  });
  const DLTensor& dl = managed->dl_tensor;
  t.device_type = static_cast<int>(dl.device.device_type);
  t.device_id = dl.device.device_id;
  t.data = static_cast<char*>(dl.data) + dl.byte_offset;
  t.dtype = dtype_of_dlpack(dl.dtype);
  const auto item = static_cast<py::ssize_t>(t.dtype.itemsize());
  t.shape.assign(dl.shape, dl.shape + dl.ndim);
  py::ssize_t elements = 1;
  for (py::ssize_t n : t.shape) elements *= n;
  if (!dl.data && elements > 0) throw py::type_error("volume.__dlpack__() gave a null data pointer");
  t.strides.resize(t.shape.size());
  py::ssize_t compact = item;  // no strides: C-contiguous
  for (int d = dl.ndim - 1; d >= 0; --d) {
    t.strides[static_cast<std::size_t>(d)] = dl.strides ? static_cast<py::ssize_t>(dl.strides[d]) * item : compact;
    compact *= t.shape[static_cast<std::size_t>(d)];
  }
  return t;
}

ForeignTensor tensor_from_cuda_array_interface(const py::object& obj) {
  const py::dict cai = obj.attr("__cuda_array_interface__");
  auto field = [&cai](const char* key) -> py::object {
    if (!cai.contains(key)) throw py::type_error(std::string("volume.__cuda_array_interface__ has no '") + key + "'");
    return cai[key];
  };
  if (cai.contains("mask") && !cai["mask"].is_none())
    throw py::type_error("volume.__cuda_array_interface__ has a mask; keymesh reads unmasked arrays");
  ForeignTensor t;
  t.device_type = static_cast<int>(TensorDevice::Cuda);
  t.dtype = py::dtype(field("typestr").cast<std::string>());
  for (const py::handle d : field("shape").cast<py::sequence>()) t.shape.push_back(d.cast<py::ssize_t>());
  t.data = reinterpret_cast<void*>(field("data").cast<py::sequence>()[0].cast<std::uintptr_t>());
  py::object strides = py::none();
  if (cai.contains("strides")) strides = cai["strides"];
  t.strides.resize(t.shape.size());
  py::ssize_t compact = t.dtype.itemsize();
  for (auto d = static_cast<py::ssize_t>(t.shape.size()) - 1; d >= 0; --d) {
    const auto k = static_cast<std::size_t>(d);
    t.strides[k] = strides.is_none() ? compact : strides.cast<py::sequence>()[k].cast<py::ssize_t>();
    compact *= t.shape[k];
  }
  if (cai.contains("stream") && !cai["stream"].is_none()) t.ready_after = cai["stream"].cast<std::uintptr_t>();
  t.owner = std::shared_ptr<void>(new py::object(obj), [](void* p) {
    py::gil_scoped_acquire gil;
    delete static_cast<py::object*>(p);
  });
  return t;
}

py::array host_array_of(ForeignTensor&& tensor) {
  auto* keep = new std::shared_ptr<void>(std::move(tensor.owner));
  const py::capsule base(keep, [](void* p) { delete static_cast<std::shared_ptr<void>*>(p); });
  return py::array(tensor.dtype, tensor.shape, tensor.strides, tensor.data, base);
}

}  // namespace keymesh::python
