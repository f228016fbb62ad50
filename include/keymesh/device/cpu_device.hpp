#pragma once
// The CPU device of the device layer (keymesh/device/algorithms.hpp says what
// a device provides): its arrays are host memory (keymesh::Array, so a
// generator's output array becomes the mesh's without a copy) and its
// primitives are keymesh/parallel's, which split every range into fixed
// chunks: results depend on the input only, never on the thread count.
//
// It is what ctest runs the generators' device paths on, so that the code the
// GPU runs (src/cuda, the CUDA device) is the code tested bit for bit against
// the CPU's own fast paths on a machine without a GPU.
#include <algorithm>
#include <chrono>
#include <cstddef>
#include <utility>

#include "keymesh/core/array.hpp"
#include "keymesh/core/types.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/parallel/scan.hpp"

namespace keymesh::device {

struct CpuDevice {
  static constexpr const char* kName = "cpu";
  // Device memory is host memory: an input is read where it lies.
  static constexpr bool kHostMemory = true;

  template <class T>
  using Array = keymesh::Array<T>;

  // n elements, unwritten.
  template <class T>
  Array<T> allocate(Id n) const {
    return Array<T>(static_cast<std::size_t>(n));
  }
  // An array the generator hands to its caller (a mesh's points, triangles,
  // fields): on the CPU the same memory as any other.
  template <class T>
  Array<T> allocate_output(Id n) const {
    return allocate<T>(n);
  }
  template <class T>
  Array<T> upload(const T* host, Id n) const {
    return Array<T>(host, host + n);
  }
  template <class T>
  void download(const T* data, Id n, T* host) const {
    std::copy(data, data + n, host);
  }
  // A device array as a host array: the same storage, moved.
  template <class T>
  keymesh::Array<T> to_host(Array<T>&& a) const {
    return std::move(a);
  }
  // One element, read back (a count the host sizes the next stage by).
  template <class T>
  T read(const T* element) const {
    return *element;
  }

  // f(i) for every i in [0, n), in parallel; f writes only what i owns.
  template <class F>
  void for_each(Id n, const F& f) const {
    parallel::for_each(n, [&f](Id i) { f(i); });
  }

  // out[i] = in[0] + ... + in[i - 1] summed in U (64 bits for counts: the
  // total of a large volume's triangles does not wrap); returns the total.
  // out may alias in.
  template <class T, class U>
  U exclusive_scan(const T* in, U* out, Id n) const {
    return parallel::exclusive_scan(in, out, n);
  }

  // Stable LSD radix sort of n (key, value) pairs in place, on the keys' low
  // significant_bits bits (unsigned keys).
  template <class K, class V>
  void sort_pairs(K* keys, V* values, Id n, int significant_bits) const {
    parallel::sort_pairs(keys, values, n, significant_bits);
  }

  void synchronize() const {}

  // Stage times (see algorithms.hpp): the host's clock, the CPU's work being
  // done when a call returns. end_stage adds the seconds to *seconds.
  struct StageMark {
    double* seconds;
    std::chrono::steady_clock::time_point begin;
  };
  StageMark begin_stage(double* seconds) const { return StageMark{seconds, std::chrono::steady_clock::now()}; }
  void end_stage(const StageMark& m) const {
    *m.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - m.begin).count();
  }
};

}  // namespace keymesh::device
