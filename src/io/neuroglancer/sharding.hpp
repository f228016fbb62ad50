#pragma once
// Neuroglancer's sharded layout ("neuroglancer_uint64_sharded_v1",
// sharded.md) for multilod meshes: a segment id, hashed with
// murmurhash3_x86_128 after a right shift by preshift_bits, picks its shard
// (bits [minishard_bits, minishard_bits + shard_bits) of the hash) and its
// minishard (bits [0, minishard_bits)). A shard file `<shard>.shard` is
//   the shard index: per minishard, [start, end) of its minishard index,
//     uint64le each, relative to the index's end;
//   every segment's fragment data followed by its manifest (the manifest is
//     the "chunk" the minishard index points at; the fragments sit right
//     before it, as meshes.md says), minishard by minishard, ids increasing;
//   the minishard indices, gzip-compressed: per minishard a C-order [3, n]
//     uint64le array of delta-encoded ids, delta-encoded starts (from the
//     previous manifest's end) and manifest sizes.
// Manifests are stored raw ("data_encoding": "raw"; the fragments are Draco
// already and the format never compresses them).
#include <cstdint>
#include <string>
#include <vector>

#include "segment_mesh.hpp"

namespace keymesh::io::neuroglancer {

struct ShardingSpec {
  int preshift_bits = 0;
  int minishard_bits = 0;
  int shard_bits = 0;
  bool operator==(const ShardingSpec&) const = default;
};

// The parameters for `segments` meshes (the rule, docs/decisions/neuroglancer-multilod.md):
// no preshift (ids carry no locality worth keeping together); about 256
// segments a shard (shard_bits = ceil(log2(ceil(segments / 256)))), and
// about 32 a minishard (minishard_bits = ceil(log2(ceil(per_shard / 32)))),
// so a reader fetches a 16-byte shard-index entry and a minishard index of
// some 750 raw bytes before a manifest.
ShardingSpec sharding_for(std::size_t segments);

std::uint64_t shard_of(const ShardingSpec& spec, std::uint64_t segment);

// "<shard>.shard", the shard number in lowercase hex padded to ceil(shard_bits / 4) digits.
std::string shard_file_name(const ShardingSpec& spec, std::uint64_t shard);

// The bytes of one shard file holding `segments` (each of this shard, any order).
std::string shard_bytes(const ShardingSpec& spec, std::vector<const SegmentFiles*> segments);

}  // namespace keymesh::io::neuroglancer
