#pragma once
// The fixture of tests run once per thread count: the parameter of
// INSTANTIATE_TEST_SUITE_P(..., ::testing::Values(1, 2, ...)) is the worker
// count during the test; all cores again after it, for the next test.
#include <gtest/gtest.h>

#include "keymesh/parallel/threads.hpp"

namespace keymesh::tests {

class ThreadCountTest : public ::testing::TestWithParam<int> {
 protected:
  void SetUp() override { parallel::set_thread_count(GetParam()); }
  void TearDown() override { parallel::set_thread_count(0); }
};

}  // namespace keymesh::tests
