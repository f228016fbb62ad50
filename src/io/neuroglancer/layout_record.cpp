// DIR/chunks/layout.json: the layout the chunk tasks were run with, so that
// a later task or the final step with other options is refused by name
// instead of mixing pieces of two layouts (declared in chunk_store.hpp).
#include <filesystem>

#include <nlohmann/json.hpp>

#include "io/mesh_bytes.hpp"
#include "chunk_store.hpp"
#include "keymesh/core/error.hpp"

namespace keymesh::io::neuroglancer {

namespace {

nlohmann::ordered_json layout_fields(const MultilodLayout& layout) {
  nlohmann::ordered_json j;
  j["chunk_shape"] = layout.chunk_shape;
  j["chunks"] = layout.chunks;
  j["grid_origin"] = layout.grid_origin;
  j["lods"] = layout.lods;
  j["transform"] = layout.transform;
  j["vertex_quantization_bits"] = layout.vertex_quantization_bits;
  j["sharded"] = layout.sharded;
  return j;
}

}  // namespace

std::string layout_record(const MultilodLayout& layout) {
  nlohmann::ordered_json record;
  record["format"] = "keymesh neuroglancer chunk pieces";
  record["version"] = 1;
  record["layout"] = layout_fields(layout);
  return record.dump(2) + "\n";
}

void check_layout_record(const std::string& dir, const MultilodLayout& layout) {
  const std::string path = layout_record_path(dir);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw InputError(path + ": no such file (no chunk task has written pieces into " + dir + " yet)");
  const mesh_bytes::FileBytes text = mesh_bytes::read_whole_file(path);
  const nlohmann::json stored = nlohmann::json::parse(text.view(), nullptr, false);
  if (stored.is_discarded() || !stored.is_object() || stored.value("format", std::string()) != "keymesh neuroglancer chunk pieces" ||
      !stored.contains("layout") || !stored["layout"].is_object())
    throw InputError(path + ": not a keymesh chunk-pieces layout record");
  const nlohmann::json current = nlohmann::json::parse(layout_fields(layout).dump());
  for (const auto& [field, value] : current.items()) {
    const auto it = stored["layout"].find(field);
    if (it == stored["layout"].end() || *it != value)
      throw InputError(path + ": the chunk pieces were written with " + field + " " +
                       (it == stored["layout"].end() ? std::string("unset") : it->dump()) + ", this run has " +
                       value.dump() + " (give every chunk task and the final step the same options, or remove " +
                       (std::filesystem::path(dir) / "chunks").string() + ")");
  }
}

}  // namespace keymesh::io::neuroglancer
