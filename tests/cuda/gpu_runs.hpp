#pragma once
// What the GPU tests share (tests/cuda/*_test.cpp): skipping, saying why,
// where keymesh was built without CUDA or no device is present; a GPU run
// compared with the CPU's and with itself; the message a refusal gives.
#include <gtest/gtest.h>

#include <functional>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/cuda/backend.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "same_bits.hpp"

#define SKIP_WITHOUT_GPU()                                     \
  do {                                                         \
    std::string why;                                           \
    if (!keymesh::cuda::available(&why)) GTEST_SKIP() << why;  \
  } while (0)

namespace keymesh::testing {

// The CPU's result, then two GPU runs: the first equal to the CPU's, the
// second to the first. `run(backend)` gives a mesh or a grid.
template <class Run>
void expect_gpu_twice(const Run& run, const std::string& what) {
  const auto cpu = run(generate::Backend::Cpu);
  const auto first = run(generate::Backend::Cuda);
  expect_same_bits(first, cpu, what + ": cuda = cpu");
  expect_same_bits(run(generate::Backend::Cuda), first, what + ": cuda run 2 = run 1");
}

// The message of the InputError `f` throws ("" when it throws none).
inline std::string refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace keymesh::testing
