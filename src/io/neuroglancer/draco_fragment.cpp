#include "draco_fragment.hpp"

#include <memory>
#include <stdexcept>

#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

namespace keymesh::io::neuroglancer {

namespace {

// Draco's speed options (0 slowest/smallest .. 10 fastest): 5 keeps the
// standard edgebreaker and the parallelogram position prediction. Faster
// settings cost the same instructions here and write 7 % more bytes; slower
// ones 4 % fewer bytes for 6 % more encoding, 12 % more decoding
// (docs/decisions/draco-speed-options.md).
constexpr int kEncodingSpeed = 5;
constexpr int kDecodingSpeed = 5;

std::unique_ptr<draco::Mesh> draco_mesh(const QuantizedMesh& mesh) {
  const std::size_t points = mesh.positions.size() / 3;
  auto out = std::make_unique<draco::Mesh>();
  out->set_num_points(static_cast<draco::PointIndex::ValueType>(points));
  draco::GeometryAttribute position;
  // Neuroglancer's decoder accepts DT_INT32 or DT_FLOAT32 positions (it reads
  // the values as uint32), not DT_UINT32.
  position.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_INT32, false,
                draco::DataTypeLength(draco::DT_INT32) * 3, 0);
  const int id = out->AddAttribute(position, true, static_cast<draco::AttributeValueIndex::ValueType>(points));
  draco::PointAttribute* attribute = out->attribute(id);
  for (std::size_t i = 0; i < points; ++i)
    attribute->SetAttributeValue(draco::AttributeValueIndex(static_cast<std::uint32_t>(i)), &mesh.positions[3 * i]);
  const std::size_t faces = mesh.triangles.size() / 3;
  out->SetNumFaces(faces);
  for (std::size_t f = 0; f < faces; ++f) {
    draco::Mesh::Face face;
    for (int c = 0; c < 3; ++c) face[c] = draco::PointIndex(mesh.triangles[3 * f + c]);
    out->SetFace(draco::FaceIndex(static_cast<std::uint32_t>(f)), face);
  }
  return out;
}

}  // namespace

std::string encode_draco_fragment(const QuantizedMesh& mesh) {
  if (mesh.triangles.empty()) return {};
  const std::unique_ptr<draco::Mesh> input = draco_mesh(mesh);
  draco::Encoder encoder;
  encoder.SetSpeedOptions(kEncodingSpeed, kDecodingSpeed);
  encoder.SetEncodingMethod(draco::MESH_EDGEBREAKER_ENCODING);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(*input, &buffer);
  if (!status.ok()) throw std::runtime_error("neuroglancer: Draco could not encode a fragment: " + status.error_msg_string());
  return std::string(buffer.data(), buffer.size());
}

}  // namespace keymesh::io::neuroglancer
