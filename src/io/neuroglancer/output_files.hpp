#pragma once
// Writing the output directory from encoded segments, through AtomicFile
// inside the caller's OutputTransaction (every file appears together, or
// none does):
//   DIR/info, DIR/segment_properties/info (when names are given),
//   unsharded: DIR/<id>.index (manifest) and DIR/<id> (fragment data) per segment,
//   sharded:   DIR/<shard>.shard per shard holding a segment.
// A full write also removes the outputs of an earlier write that this one
// does not hold (files named like a segment's, a shard's, or the segment
// properties), so the directory equals a fresh write's. A partial write
// (`--update`) rewrites only the segments or shards it is given, removing
// those that became empty.
#include <cstdint>
#include <functional>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "keymesh/io/neuroglancer.hpp"
#include "segment_mesh.hpp"
#include "sharding.hpp"

namespace keymesh::io::neuroglancer {

struct OutputScope {
  bool full = true;
  std::vector<std::uint64_t> segments;  // partial and unsharded: the segments rewritten
  std::vector<std::uint64_t> shards;    // partial and sharded: the shards rewritten
};

// Every group's segment encoded (in parallel; the result does not depend on
// the thread count), the segments without a mesh left out. `beside`, when
// given, runs on the calling thread meanwhile (parallel/for_each_task_beside.hpp):
// the first segment's error is thrown before its own.
std::vector<SegmentFiles> encode_segments(const MultilodLayout& layout,
                                          const std::vector<std::pair<std::uint64_t, std::vector<const ChunkPiece*>>>& groups,
                                          const std::function<void()>& beside = {});

// The sharding of a layout whose output holds `segments` meshes (nullopt: unsharded).
std::optional<ShardingSpec> sharding_of(const MultilodLayout& layout, std::size_t segments);

void write_output(const std::string& dir, const MultilodLayout& layout, const std::vector<SegmentFiles>& segments,
                  const SegmentNames& names, const std::optional<ShardingSpec>& sharding, const OutputScope& scope);

// The full output written in parts (the final step's batches): the
// constructor writes info and the segment properties, each add() the files
// of some segments (sharded: every segment of a shard in one call), finish()
// removes the earlier outputs no part wrote. The files equal write_output's.
class OutputParts {
 public:
  OutputParts(const std::string& dir, const MultilodLayout& layout, const SegmentNames& names,
              const std::optional<ShardingSpec>& sharding);
  void add(const std::vector<SegmentFiles>& segments, const OutputScope& scope = {});
  void finish();

 private:
  std::string dir_;
  std::optional<ShardingSpec> sharding_;
  std::set<std::string> written_;
};

}  // namespace keymesh::io::neuroglancer
