#include "info_json.hpp"

#include <nlohmann/json.hpp>

namespace keymesh::io::neuroglancer {

namespace {

using ordered_json = nlohmann::ordered_json;

ordered_json sharding_json(const ShardingSpec& spec) {
  ordered_json s;
  s["@type"] = "neuroglancer_uint64_sharded_v1";
  s["preshift_bits"] = spec.preshift_bits;
  s["hash"] = "murmurhash3_x86_128";
  s["minishard_bits"] = spec.minishard_bits;
  s["shard_bits"] = spec.shard_bits;
  s["minishard_index_encoding"] = "gzip";
  s["data_encoding"] = "raw";
  return s;
}

}  // namespace

std::string info_json(const MultilodLayout& layout, const std::optional<ShardingSpec>& sharding, bool has_names) {
  ordered_json info;
  info["@type"] = "neuroglancer_multilod_draco";
  info["vertex_quantization_bits"] = layout.vertex_quantization_bits;
  info["transform"] = layout.transform;
  info["lod_scale_multiplier"] = 1.0;
  if (has_names) info["segment_properties"] = kSegmentPropertiesDir;
  if (sharding) info["sharding"] = sharding_json(*sharding);
  return info.dump(2, ' ', false, ordered_json::error_handler_t::replace) + "\n";
}

std::string segment_properties_json(const SegmentNames& names) {
  ordered_json ids = ordered_json::array(), values = ordered_json::array();
  for (const auto& [id, name] : names) {
    ids.push_back(std::to_string(id));
    values.push_back(name);
  }
  ordered_json label;
  label["id"] = "label";
  label["type"] = "label";
  label["values"] = std::move(values);
  ordered_json properties;
  properties["@type"] = "neuroglancer_segment_properties";
  properties["inline"]["ids"] = std::move(ids);
  properties["inline"]["properties"] = ordered_json::array({std::move(label)});
  // A name that is not UTF-8 has its bad bytes replaced (U+FFFD): JSON holds text only.
  return properties.dump(2, ' ', false, ordered_json::error_handler_t::replace) + "\n";
}

}  // namespace keymesh::io::neuroglancer
