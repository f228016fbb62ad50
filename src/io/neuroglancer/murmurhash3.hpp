#pragma once
// MurmurHash3_x86_128 (Austin Appleby's public-domain hash), which
// Neuroglancer's sharded format applies to a chunk id to choose its shard
// and minishard ("hash": "murmurhash3_x86_128" in sharded.md). No Debian
// package ships it for C++; it is small enough to keep here.
#include <array>
#include <cstddef>
#include <cstdint>

namespace keymesh::io::neuroglancer {

// The 128-bit hash of `size` bytes as four 32-bit words h1..h4 (the
// reference implementation's output, stored little endian, is these words
// in order).
std::array<std::uint32_t, 4> murmurhash3_x86_128(const void* data, std::size_t size, std::uint32_t seed);

// The sharded format's hash of a chunk id: MurmurHash3_x86_128 of the id's
// 8 little-endian bytes with seed 0, its low 8 bytes read as a little-endian
// 64-bit number (h2 << 32 | h1).
std::uint64_t sharding_hash(std::uint64_t id);

}  // namespace keymesh::io::neuroglancer
