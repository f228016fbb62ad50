// The .glb writer, checked by parsing the file back with tinygltf's own
// loader (Debian libtinygltf-dev, not keymesh code): the positions, normals,
// scalar attribute and indices it finds must be the mesh's arrays, bit for
// bit, and the accessor bounds the ones recomputed here.
#include "io/mesh_formats.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/io/mesh_io.hpp"

#ifdef KEYMESH_HAVE_TINYGLTF
#include <tiny_gltf.h>
#endif

using namespace keymesh;
namespace fs = std::filesystem;

namespace {

std::string temp_glb(const std::string& name) {
  return (fs::temp_directory_path() / ("keymesh_gltf_" + std::to_string(::getpid()) + "_" + name + ".glb")).string();
}

#ifdef KEYMESH_HAVE_TINYGLTF
tinygltf::Model load(const std::string& path) {
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string err, warn;
  const bool ok = loader.LoadBinaryFromFile(&model, &err, &warn, path);
  EXPECT_TRUE(ok) << err;
  EXPECT_EQ(err, "");
  EXPECT_EQ(warn, "");
  return model;
}

// The bytes an accessor designates, as T (tightly packed: no byteStride).
template <class T>
Array<T> accessor_values(const tinygltf::Model& m, int accessor, int components) {
  const tinygltf::Accessor& a = m.accessors.at(accessor);
  const tinygltf::BufferView& v = m.bufferViews.at(a.bufferView);
  EXPECT_EQ(v.byteStride, 0u);
  EXPECT_EQ((v.byteOffset + a.byteOffset) % 4, 0u) << "glTF requires aligned accessors";
  const auto& data = m.buffers.at(v.buffer).data;
  const std::size_t n = a.count * components;
  EXPECT_LE(v.byteOffset + a.byteOffset + n * sizeof(T), data.size());
  Array<T> out(n);
  std::memcpy(out.data(), data.data() + v.byteOffset + a.byteOffset, n * sizeof(T));
  return out;
}

// Per-component min and max recomputed here, as doubles.
void expect_bounds(const tinygltf::Accessor& a, const Array<float>& values, int components) {
  ASSERT_EQ(a.minValues.size(), static_cast<std::size_t>(components));
  ASSERT_EQ(a.maxValues.size(), static_cast<std::size_t>(components));
  for (int c = 0; c < components; ++c) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (std::size_t i = c; i < values.size(); i += components) lo = std::min<double>(lo, values[i]), hi = std::max<double>(hi, values[i]);
    EXPECT_EQ(a.minValues[c], lo) << "component " << c;
    EXPECT_EQ(a.maxValues[c], hi) << "component " << c;
  }
}
#endif

SurfaceMesh sphere_with_normals() {
  const ImageGrid g = generate::spherical_distance(24);
  generate::ContourOptions opt;
  opt.isovalues = {9.5};
  opt.normals = generate::ContourNormals::Average;
  return generate::contour(g, opt);
}

}  // namespace

TEST(Gltf, ContourReadsBackBitForBit) {
#ifndef KEYMESH_HAVE_TINYGLTF
  GTEST_SKIP() << "tinygltf not found (Debian libtinygltf-dev)";
#else
  const SurfaceMesh mesh = sphere_with_normals();
  ASSERT_GT(mesh.num_cells(), 100);
  const Field* normals = mesh.find_point_field("Normals");
  const Field* scalars = nullptr;  // the contoured field, named after the grid's array
  for (const Field& f : mesh.point_fields)
    if (f.name != "Normals") scalars = &f;
  ASSERT_TRUE(normals && scalars);
  std::string attribute = "_";
  for (char c : scalars->name) attribute += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  const std::string path = temp_glb("sphere");
  io::write_mesh(mesh, path);  // through the format dispatch
  EXPECT_EQ(fs::file_size(path) % 4, 0u);
  const tinygltf::Model m = load(path);
  fs::remove(path);
  EXPECT_EQ(m.asset.version, "2.0");
  ASSERT_EQ(m.meshes.size(), 1u);
  ASSERT_EQ(m.meshes[0].primitives.size(), 1u);
  const tinygltf::Primitive& prim = m.meshes[0].primitives[0];
  EXPECT_EQ(prim.mode, TINYGLTF_MODE_TRIANGLES);
  ASSERT_EQ(m.buffers.size(), 1u);

  const int pos = prim.attributes.at("POSITION");
  EXPECT_EQ(m.accessors[pos].componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);
  EXPECT_EQ(m.accessors[pos].type, TINYGLTF_TYPE_VEC3);
  EXPECT_EQ(accessor_values<float>(m, pos, 3), mesh.points);
  expect_bounds(m.accessors[pos], mesh.points, 3);

  const int nrm = prim.attributes.at("NORMAL");
  EXPECT_EQ(accessor_values<float>(m, nrm, 3), normals->values);
  expect_bounds(m.accessors[nrm], normals->values, 3);

  const int sc = prim.attributes.at(attribute);
  EXPECT_EQ(m.accessors[sc].type, TINYGLTF_TYPE_SCALAR);
  EXPECT_EQ(accessor_values<float>(m, sc, 1), scalars->values);

  const tinygltf::Accessor& idx = m.accessors.at(prim.indices);
  EXPECT_EQ(idx.componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
  EXPECT_EQ(idx.count, mesh.connectivity.size());
  EXPECT_EQ(accessor_values<std::uint32_t>(m, prim.indices, 1), mesh.connectivity);
  EXPECT_EQ(m.bufferViews[idx.bufferView].target, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
  EXPECT_EQ(m.bufferViews[m.accessors[pos].bufferView].target, TINYGLTF_TARGET_ARRAY_BUFFER);
#endif
}

TEST(Gltf, PolygonsBecomeFans) {
#ifndef KEYMESH_HAVE_TINYGLTF
  GTEST_SKIP() << "tinygltf not found (Debian libtinygltf-dev)";
#else
  // A quad and a pentagon around a fan; a 2-point cell has no triangle.
  SurfaceMesh mesh;
  mesh.points = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0, 0, 2, 1, 0, 1.5f, 2, 0};
  mesh.connectivity = {0, 1, 2, 3, /**/ 1, 4, 5, 6, 2, /**/ 0, 1};
  mesh.offsets = {0, 4, 9, 11};
  mesh.point_fields.push_back(Field{"mean curvature", 1, {1, 2, 3, 4, 5, 6, 7}});
  const std::string path = temp_glb("fans");
  io::write_mesh(mesh, path);
  const tinygltf::Model m = load(path);
  fs::remove(path);
  const tinygltf::Primitive& prim = m.meshes.at(0).primitives.at(0);
  EXPECT_EQ(prim.attributes.count("NORMAL"), 0u);
  EXPECT_EQ(accessor_values<float>(m, prim.attributes.at("_MEAN_CURVATURE"), 1), mesh.point_fields[0].values);
  const Array<std::uint32_t> expected = {0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 6, 1, 6, 2};
  EXPECT_EQ(accessor_values<std::uint32_t>(m, prim.indices, 1), expected);
#endif
}

TEST(Gltf, EmptyMeshIsAValidSceneWithoutBuffers) {
#ifndef KEYMESH_HAVE_TINYGLTF
  GTEST_SKIP() << "tinygltf not found (Debian libtinygltf-dev)";
#else
  const std::string path = temp_glb("empty");
  io::write_mesh(SurfaceMesh{}, path);
  const tinygltf::Model m = load(path);
  fs::remove(path);
  EXPECT_TRUE(m.meshes.empty());
  EXPECT_TRUE(m.buffers.empty());
  ASSERT_EQ(m.nodes.size(), 1u);
  EXPECT_EQ(m.nodes[0].mesh, -1);
#endif
}
