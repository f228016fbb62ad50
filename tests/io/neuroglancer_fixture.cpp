// Test-only program: writes the synthetic Neuroglancer multilod dataset of
// neuroglancer_dataset.hpp, so that the independent Python reader
// (tests/neuroglancer_precomputed.py) can check the writer end to end
// before the CLI's `--format precomputed` exists.
//
//   keymesh_neuroglancer_fixture DIR [--sharded] [--bits 10|16] [--many N]
//                                    [--chunked] [--names] [--dump FILE]
//
// --many N: N small boxes (several shards) instead of the four default ones;
// --chunked: through write_chunk_pieces per chunk + assemble_multilod;
// --dump FILE: the input pieces and layout as JSON, for the comparisons.
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "io/neuroglancer_dataset.hpp"
#include "keymesh/io/neuroglancer.hpp"

namespace ng = keymesh::io::neuroglancer;
namespace dataset = keymesh::tests::neuroglancer_dataset;

namespace {

void dump(const std::string& path, const ng::MultilodLayout& layout, const std::vector<ng::ChunkPiece>& pieces) {
  nlohmann::json j;
  j["layout"] = {{"chunk_shape", layout.chunk_shape}, {"chunks", layout.chunks}, {"grid_origin", layout.grid_origin},
                 {"lods", layout.lods}, {"vertex_quantization_bits", layout.vertex_quantization_bits},
                 {"transform", layout.transform}};
  j["pieces"] = nlohmann::json::array();
  for (const auto& p : pieces)
    j["pieces"].push_back({{"segment", p.segment}, {"lod", p.lod}, {"chunk", p.chunk}, {"keys", p.point_keys},
                           {"points", p.points}, {"triangles", p.triangles}});
  std::ofstream(path) << j.dump() << "\n";
}

void write_chunked(const std::string& dir, const ng::MultilodLayout& layout, const std::vector<ng::ChunkPiece>& pieces,
                   const ng::SegmentNames& names) {
  std::map<std::array<std::uint32_t, 3>, std::vector<ng::ChunkPiece>> chunks;
  for (std::uint32_t z = 0; z < layout.chunks[2]; ++z)
    for (std::uint32_t y = 0; y < layout.chunks[1]; ++y)
      for (std::uint32_t x = 0; x < layout.chunks[0]; ++x) chunks[{x, y, z}];
  for (const auto& p : pieces) chunks[p.chunk].push_back(p);
  for (const auto& [chunk, mine] : chunks) ng::write_chunk_pieces(dir, layout, chunk, mine);
  ng::assemble_multilod(dir, layout, {}, names);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: keymesh_neuroglancer_fixture DIR [--sharded] [--bits 10|16] [--many N] [--chunked] [--names] [--dump FILE]\n";
    return 2;
  }
  const std::string dir = argv[1];
  bool sharded = false, chunked = false, named = false;
  int bits = 16;
  long many = 0;
  std::string dump_path;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--sharded") sharded = true;
    else if (a == "--chunked") chunked = true;
    else if (a == "--names") named = true;
    else if (a == "--bits" && i + 1 < argc) bits = std::atoi(argv[++i]);
    else if (a == "--many" && i + 1 < argc) many = std::atol(argv[++i]);
    else if (a == "--dump" && i + 1 < argc) dump_path = argv[++i];
    else {
      std::cerr << "keymesh_neuroglancer_fixture: unknown argument " << a << "\n";
      return 2;
    }
  }
  try {
    ng::MultilodLayout layout = dataset::layout(sharded);
    layout.vertex_quantization_bits = bits;
    const auto boxes = many > 0 ? dataset::many_boxes(static_cast<std::uint64_t>(many)) : dataset::boxes();
    const auto pieces = dataset::pieces(layout, boxes);
    ng::SegmentNames names;
    if (named)
      for (const auto& b : boxes) names[b.segment] = "box " + std::to_string(b.segment);
    if (chunked)
      write_chunked(dir, layout, pieces, names);
    else
      ng::write_multilod(dir, layout, pieces, names);
    if (!dump_path.empty()) dump(dump_path, layout, pieces);
  } catch (const std::exception& e) {
    std::cerr << "keymesh_neuroglancer_fixture: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
