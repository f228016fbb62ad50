// A fragment's Draco bytes, decoded by Draco's own decoder: the int32
// positions come back exactly (no Draco quantization: the format forbids
// it), a zero-area triangle handed to the encoder is kept (the writer
// merges points on one integer point before: coincident_points.hpp), the
// bytes are the same on every call, and an empty node is 0 bytes.
#include "io/neuroglancer/draco_fragment.hpp"

#include <draco/compression/decode.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

using namespace keymesh::io::neuroglancer;

namespace {

struct Decoded {
  std::multiset<std::array<std::int32_t, 3>> positions;  // of the faces' corners
  std::size_t faces = 0;
  std::size_t zero_area = 0;
};

Decoded decode(const std::string& bytes) {
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  EXPECT_TRUE(decoded.ok());
  Decoded out;
  if (!decoded.ok()) return out;
  const std::unique_ptr<draco::Mesh> mesh = std::move(decoded).value();
  const draco::PointAttribute* position = mesh->GetNamedAttribute(draco::GeometryAttribute::POSITION);
  EXPECT_EQ(position->data_type(), draco::DT_INT32);
  EXPECT_EQ(position->size(), mesh->num_points()) << "Neuroglancer's decoder needs one value a point";
  out.faces = mesh->num_faces();
  for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f) {
    std::array<std::array<std::int32_t, 3>, 3> corner;
    for (int c = 0; c < 3; ++c) {
      position->GetValue(position->mapped_index(mesh->face(f)[c]), corner[c].data());
      out.positions.insert(corner[c]);
    }
    out.zero_area += corner[0] == corner[1] && corner[1] == corner[2];
  }
  return out;
}

TEST(NeuroglancerDracoFragment, PositionsExactDegenerateKeptBytesStable) {
  QuantizedMesh mesh;
  mesh.positions = {0, 0, 0, 65535, 0, 0, 0, 65535, 0, 65535, 65535, 0, 12345, 32768, 1, 12345, 32768, 1, 12345, 32768, 1};
  mesh.triangles = {0, 1, 2, 1, 3, 2, 4, 5, 6};  // the last: three points quantized to one
  const std::string bytes = encode_draco_fragment(mesh);
  EXPECT_EQ(bytes, encode_draco_fragment(mesh));
  const Decoded d = decode(bytes);
  EXPECT_EQ(d.faces, 3u);
  EXPECT_EQ(d.zero_area, 1u);
  std::multiset<std::array<std::int32_t, 3>> expected;
  for (std::uint32_t corner : mesh.triangles)
    expected.insert({mesh.positions[3 * corner], mesh.positions[3 * corner + 1], mesh.positions[3 * corner + 2]});
  EXPECT_EQ(d.positions, expected);
}

TEST(NeuroglancerDracoFragment, EmptyNodeIsZeroBytes) {
  QuantizedMesh mesh;
  mesh.positions = {1, 2, 3};
  EXPECT_EQ(encode_draco_fragment(mesh), "");
}

}  // namespace
