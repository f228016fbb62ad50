#pragma once
// A tensor of another array library (PyTorch, CuPy, JAX, numpy itself),
// received through DLPack (a "dltensor" capsule from __dlpack__) or
// __cuda_array_interface__, as keymesh reads it: where its samples are, their
// type and layout, and what keeps them alive. Nothing is copied.
#include <cstdint>
#include <memory>
#include <vector>

#include "common.hpp"

namespace keymesh::python {

// DLPack's device types keymesh meets (dlpack.h's DLDeviceType).
enum class TensorDevice { Cpu = 1, Cuda = 2, CudaHost = 3 };

struct ForeignTensor {
  int device_type = 1;  // DLDeviceType: 1 CPU, 2 CUDA, 3 CUDA pinned host memory
  int device_id = -1;   // -1: not said (__cuda_array_interface__): the pointer's device
  void* data = nullptr;  // element [0, ..., 0] (DLPack's data + byte_offset)
  py::dtype dtype;       // numpy's spelling of the element type
  std::vector<py::ssize_t> shape, strides;  // strides in bytes
  // __cuda_array_interface__'s "stream" (its work must end before the data
  // are read), or 1 after __dlpack__(stream=1); 0: ready.
  std::uintptr_t ready_after = 0;
  std::shared_ptr<void> owner;  // the producer's deleter, or a reference to the producer

  bool on_cuda() const { return device_type == static_cast<int>(TensorDevice::Cuda); }
  // C- or Fortran-contiguous (a size-1 axis's stride does not count).
  bool contiguous(bool fortran) const;
};

// The tensor of a "dltensor" capsule (from obj.__dlpack__()), which is
// consumed (renamed "used_dltensor"; the producer's deleter runs when the
// last copy of `owner` goes). TypeError for a capsule of another name, an
// element type numpy has no name for (bfloat16, vectors of lanes).
ForeignTensor tensor_from_dlpack(const py::capsule& capsule);
// The tensor an object's __cuda_array_interface__ (version 2 or 3)
// describes; `owner` keeps the object. TypeError for a mask, a malformed
// dictionary.
ForeignTensor tensor_from_cuda_array_interface(const py::object& obj);
// A host tensor as a numpy array over the same memory (the tensor's owner
// as its base): what keymesh.contour then reads as any numpy array.
py::array host_array_of(ForeignTensor&& tensor);

// keymesh.DeviceArray: a mesh array in device memory handed to Python,
// exporting itself by DLPack and __cuda_array_interface__ (device_array.cpp).
void register_device_array(py::module_& m);
// The exporter over device memory: `buffer` keeps it, `data` its first
// element, shape C-contiguous, dtype one of numpy's.
py::object device_array(std::shared_ptr<void> buffer, void* data, int device_type, int device_id,
                        const py::dtype& dtype, std::vector<py::ssize_t> shape);

}  // namespace keymesh::python
