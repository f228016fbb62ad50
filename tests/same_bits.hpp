#pragma once
// Bit-for-bit comparison of meshes (the device paths' tests): every array's
// bytes, so that -0 and +0 differ and a NaN equals only the same NaN, which
// EXPECT_EQ on floats would not see.
#include <gtest/gtest.h>

#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "keymesh/mesh/surface_mesh.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::testing {

// Empty when a and b hold the same bytes; otherwise where they first differ.
template <class A, class B>
std::string first_difference(const A& a, const B& b) {
  std::ostringstream why;
  if (a.size() != b.size()) {
    why << "sizes " << a.size() << " and " << b.size();
    return why.str();
  }
  using T = typename A::value_type;
  static_assert(sizeof(T) == sizeof(typename B::value_type), "arrays of the same element size");
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::memcmp(&a[i], &b[i], sizeof(T)) != 0) {
      why << "element " << i << " of " << a.size() << ": " << +a[i] << " and " << +b[i];
      return why.str();
    }
  return {};
}

inline void expect_same_fields(const std::vector<Field>& a, const std::vector<Field>& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t f = 0; f < a.size(); ++f) {
    EXPECT_EQ(a[f].name, b[f].name) << what;
    EXPECT_EQ(a[f].components, b[f].components) << what << " " << a[f].name;
    EXPECT_EQ(first_difference(a[f].values, b[f].values), "") << what << " field " << a[f].name;
  }
}

inline void expect_same_bits(const SurfaceMesh& a, const SurfaceMesh& b, const std::string& what) {
  EXPECT_EQ(first_difference(a.points, b.points), "") << what << " points";
  EXPECT_EQ(first_difference(a.connectivity, b.connectivity), "") << what << " connectivity";
  EXPECT_EQ(first_difference(a.offsets, b.offsets), "") << what << " offsets";
  expect_same_fields(a.point_fields, b.point_fields, what + " point fields");
  expect_same_fields(a.cell_fields, b.cell_fields, what + " cell fields");
}

// Tetrahedral (or any unstructured) grids: the connectivity's width too.
inline void expect_same_bits(const UnstructuredGrid& a, const UnstructuredGrid& b, const std::string& what) {
  EXPECT_EQ(first_difference(a.points, b.points), "") << what << " points";
  ASSERT_EQ(a.connectivity.wide(), b.connectivity.wide()) << what << " connectivity width";
  if (b.connectivity.wide())
    EXPECT_EQ(first_difference(a.connectivity.wide_values(), b.connectivity.wide_values()), "") << what << " connectivity";
  else
    EXPECT_EQ(first_difference(a.connectivity.narrow(), b.connectivity.narrow()), "") << what << " connectivity";
  EXPECT_EQ(a.uniform_type, b.uniform_type) << what;
  EXPECT_EQ(a.offsets, b.offsets) << what;
  EXPECT_EQ(a.cell_types, b.cell_types) << what;
  expect_same_fields(a.point_fields, b.point_fields, what + " point fields");
  expect_same_fields(a.cell_fields, b.cell_fields, what + " cell fields");
}

}  // namespace keymesh::testing
