#include "manifest.hpp"

#include <bit>
#include <cmath>
#include <cstring>

namespace keymesh::io::neuroglancer {

namespace {

static_assert(std::endian::native == std::endian::little, "the manifest is written as the host's little-endian words");

template <class T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

}  // namespace

std::string manifest_bytes(const MultilodLayout& layout, const std::vector<LodFragments>& lods) {
  std::string out;
  for (std::uint32_t c : layout.chunk_shape) put(out, static_cast<float>(c));
  for (float o : layout.grid_origin) put(out, o);
  const auto num_lods = static_cast<std::uint32_t>(lods.size());
  put(out, num_lods);
  for (std::uint32_t lod = 0; lod < num_lods; ++lod) put(out, std::ldexp(1.0f, static_cast<int>(lod)));
  for (std::uint32_t i = 0; i < 3 * num_lods; ++i) put(out, 0.0f);
  for (const LodFragments& lod : lods) put(out, static_cast<std::uint32_t>(lod.positions.size()));
  for (const LodFragments& lod : lods) {
    for (int axis = 0; axis < 3; ++axis)
      for (const NodePosition& p : lod.positions) put(out, p[axis]);
    for (std::uint32_t size : lod.sizes) put(out, size);
  }
  return out;
}

}  // namespace keymesh::io::neuroglancer
