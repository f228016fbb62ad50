#include "murmurhash3.hpp"

namespace keymesh::io::neuroglancer {

namespace {

constexpr std::uint32_t kC1 = 0x239b961b, kC2 = 0xab0e9789, kC3 = 0x38b34ae5, kC4 = 0xa1e38b93;

constexpr std::uint32_t rotl(std::uint32_t x, int r) { return (x << r) | (x >> (32 - r)); }

constexpr std::uint32_t fmix(std::uint32_t h) {
  h ^= h >> 16;
  h *= 0x85ebca6b;
  h ^= h >> 13;
  h *= 0xc2b2ae35;
  h ^= h >> 16;
  return h;
}

// Little-endian word of `n` bytes (n <= 4) at p, whatever the host's order.
std::uint32_t word(const unsigned char* p, std::size_t n) {
  std::uint32_t w = 0;
  for (std::size_t i = 0; i < n; ++i) w |= std::uint32_t{p[i]} << (8 * i);
  return w;
}

// The four lanes' key mixes: lane j multiplies by C[j], rotates, multiplies by C[j+1].
constexpr std::array<std::uint32_t, 5> kLaneC = {kC1, kC2, kC3, kC4, kC1};
constexpr std::array<int, 4> kLaneRotation = {15, 16, 17, 18};

std::uint32_t mix_key(std::uint32_t k, int lane) {
  k *= kLaneC[lane];
  k = rotl(k, kLaneRotation[lane]);
  return k * kLaneC[lane + 1];
}

}  // namespace

std::array<std::uint32_t, 4> murmurhash3_x86_128(const void* data, std::size_t size, std::uint32_t seed) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  std::array<std::uint32_t, 4> h = {seed, seed, seed, seed};
  constexpr std::array<int, 4> kHashRotation = {19, 17, 15, 13};
  constexpr std::array<std::uint32_t, 4> kHashAdd = {0x561ccd1b, 0x0bcaa747, 0x96cd1c35, 0x32ac3b17};
  const std::size_t blocks = size / 16;
  for (std::size_t b = 0; b < blocks; ++b)
    for (int lane = 0; lane < 4; ++lane) {
      h[lane] ^= mix_key(word(bytes + 16 * b + 4 * lane, 4), lane);
      h[lane] = rotl(h[lane], kHashRotation[lane]);
      h[lane] += h[(lane + 1) & 3];
      h[lane] = h[lane] * 5 + kHashAdd[lane];
    }
  // The tail: up to 15 bytes, lane by lane, each lane's word mixed without
  // the hash-state rotation (the reference's switch fall-through).
  const unsigned char* tail = bytes + 16 * blocks;
  const std::size_t rest = size & 15;
  for (int lane = 0; lane < 4; ++lane) {
    const std::size_t begin = 4 * static_cast<std::size_t>(lane);
    if (rest > begin) h[lane] ^= mix_key(word(tail + begin, rest - begin < 4 ? rest - begin : 4), lane);
  }
  for (auto& x : h) x ^= static_cast<std::uint32_t>(size);
  h[0] += h[1] + h[2] + h[3];
  h[1] += h[0], h[2] += h[0], h[3] += h[0];
  for (auto& x : h) x = fmix(x);
  h[0] += h[1] + h[2] + h[3];
  h[1] += h[0], h[2] += h[0], h[3] += h[0];
  return h;
}

std::uint64_t sharding_hash(std::uint64_t id) {
  unsigned char bytes[8];
  for (int i = 0; i < 8; ++i) bytes[i] = static_cast<unsigned char>(id >> (8 * i));
  const std::array<std::uint32_t, 4> h = murmurhash3_x86_128(bytes, sizeof bytes, 0);
  return std::uint64_t{h[1]} << 32 | h[0];
}

}  // namespace keymesh::io::neuroglancer
