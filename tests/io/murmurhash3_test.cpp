// MurmurHash3_x86_128 against published values: tensorstore's test vectors
// for 8-byte inputs (neuroglancer_uint64_sharded murmurhash3_test.cc,
// computed with pymmh3) and SMHasher's verification value for the whole
// function (every length 0..255, so every tail length and several blocks).
#include "io/neuroglancer/murmurhash3.hpp"

#include <gtest/gtest.h>

#include <cstdint>

using namespace keymesh::io::neuroglancer;

namespace {

std::array<std::uint32_t, 4> hash_u64(std::uint64_t value, std::uint32_t seed) {
  unsigned char bytes[8];
  for (int i = 0; i < 8; ++i) bytes[i] = static_cast<unsigned char>(value >> (8 * i));
  return murmurhash3_x86_128(bytes, 8, seed);
}

TEST(Murmurhash3, TensorstoreVectorsForEightBytes) {
  struct Vector {
    std::uint64_t input;
    std::uint32_t seed, h1, h2;
  };
  const Vector vectors[] = {{0, 0, 0xe028ae41, 0x4772b084},  {0, 1, 0x5ad58a7e, 0x54337108},
                            {1, 0, 0x16d4ce9a, 0xe8bd67d6},  {1, 1, 0x4b7ab8c6, 0xeb555955},
                            {1, 2, 0xeb2301be, 0x48e12494},  {42, 0, 0x5119f47a, 0xc20b94f9},
                            {42, 1, 0xd6b51bca, 0xa25ad86b}, {42, 2, 0x2d83d9c7, 0x082115eb}};
  for (const Vector& v : vectors) {
    const auto h = hash_u64(v.input, v.seed);
    EXPECT_EQ(h[0], v.h1) << v.input << " seed " << v.seed;
    // For 8 bytes, h2 = h3 = h4 (the lanes 3 and 4 see no key).
    EXPECT_EQ(h[1], v.h2);
    EXPECT_EQ(h[2], v.h2);
    EXPECT_EQ(h[3], v.h2);
  }
}

TEST(Murmurhash3, ShardingHashIsTheLowEightBytes) {
  EXPECT_EQ(sharding_hash(0), 0x4772b084e028ae41ull);
  EXPECT_EQ(sharding_hash(42), 0xc20b94f95119f47aull);
}

TEST(Murmurhash3, SmhasherVerificationValue) {
  unsigned char key[256];
  unsigned char hashes[16 * 256];
  for (int i = 0; i < 256; ++i) {
    key[i] = static_cast<unsigned char>(i);
    const auto h = murmurhash3_x86_128(key, static_cast<std::size_t>(i), static_cast<std::uint32_t>(256 - i));
    for (int w = 0; w < 4; ++w)
      for (int b = 0; b < 4; ++b) hashes[16 * i + 4 * w + b] = static_cast<unsigned char>(h[w] >> (8 * b));
  }
  const auto final_hash = murmurhash3_x86_128(hashes, sizeof hashes, 0);
  EXPECT_EQ(final_hash[0], 0xB3ECE62Au);  // SMHasher's "Murmur3C" entry
}

TEST(Murmurhash3, EmptyInputWithSeedZeroIsZero) {
  const auto h = murmurhash3_x86_128(nullptr, 0, 0);
  for (std::uint32_t w : h) EXPECT_EQ(w, 0u);
}

}  // namespace
