#pragma once
// One octree node's mesh as the Draco bytes Neuroglancer's multilod format
// stores: a triangular mesh whose position attribute is 3 x int32, each
// value a quantized coordinate in [0, 2^bits) over the node's box. Draco's
// own attribute quantization is never used (the format forbids it): the
// integers are encoded losslessly.
#include <cstdint>
#include <string>
#include <vector>

namespace keymesh::io::neuroglancer {

struct QuantizedMesh {
  std::vector<std::int32_t> positions;   // x,y,z per point, each in [0, 2^bits)
  std::vector<std::uint32_t> triangles;  // 3 per triangle
};

// Draco edgebreaker bytes of `mesh` (deterministic: the same bytes for the
// same mesh). An empty mesh (no triangles) is 0 bytes, as the format lists
// an empty node. Throws std::runtime_error if Draco refuses the mesh.
std::string encode_draco_fragment(const QuantizedMesh& mesh);

}  // namespace keymesh::io::neuroglancer
