#pragma once
// The output's JSON files: DIR/info (meshes.md, "Multi-resolution mesh info
// JSON file format") and, when segments have names, DIR/segment_properties/info
// (segment_properties.md: inline ids and one "label" property). Keys in a
// fixed order, so the same layout always gives the same bytes.
#include <optional>
#include <string>

#include "keymesh/io/neuroglancer.hpp"
#include "sharding.hpp"

namespace keymesh::io::neuroglancer {

// The segment properties' subdirectory, named by the info.
inline constexpr const char* kSegmentPropertiesDir = "segment_properties";

std::string info_json(const MultilodLayout& layout, const std::optional<ShardingSpec>& sharding, bool has_names);

std::string segment_properties_json(const SegmentNames& names);

}  // namespace keymesh::io::neuroglancer
