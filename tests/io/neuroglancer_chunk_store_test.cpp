// The chunk tasks' store refuses what it did not write whole: a truncated,
// corrupted or foreign pieces file, a task or final step with another
// layout, and a final step before every chunk's task has run; each a clear
// InputError naming the file, and nothing assembled from it.
#include <gtest/gtest.h>

#include <fstream>

#include "io/neuroglancer_dataset.hpp"
#include "io/neuroglancer_test_files.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/io/neuroglancer.hpp"

using namespace keymesh;
using namespace keymesh::tests;
namespace ng = keymesh::io::neuroglancer;
namespace fs = std::filesystem;

namespace {

// The message of the InputError `f` throws ("" when it throws none).
template <class F>
std::string input_error(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

struct Store {
  ng::MultilodLayout layout = neuroglancer_dataset::layout();
  fs::path dir;
  fs::path file;  // chunk (1, 1, 1)'s pieces
  explicit Store(const std::string& name) : dir(neuroglancer_files::fresh_dir(name)) {
    std::vector<ng::ChunkPiece> mine;
    for (auto& p : neuroglancer_dataset::pieces(layout, neuroglancer_dataset::boxes()))
      if (p.chunk == std::array<std::uint32_t, 3>{1, 1, 1}) mine.push_back(std::move(p));
    ng::write_chunk_pieces(dir.string(), layout, {1, 1, 1}, mine);
    file = dir / "chunks" / "1_1_1.pieces";
  }
  void overwrite(const std::string& bytes) const { std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes; }
  std::string read_error() const { return input_error([&] { ng::read_chunk_pieces(dir.string(), {1, 1, 1}); }); }
};

TEST(NeuroglancerChunkStore, TruncatedFileRefused) {
  const Store store("truncated");
  const std::string bytes = neuroglancer_files::bytes_of(store.file);
  ASSERT_GT(bytes.size(), 100u);
  store.overwrite(bytes.substr(0, bytes.size() - 5));
  EXPECT_NE(store.read_error().find("truncated"), std::string::npos) << store.read_error();
  store.overwrite(bytes.substr(0, 20));
  EXPECT_NE(store.read_error().find("not a keymesh chunk-pieces file"), std::string::npos) << store.read_error();
}

TEST(NeuroglancerChunkStore, CorruptedPayloadRefused) {
  const Store store("corrupted");
  std::string bytes = neuroglancer_files::bytes_of(store.file);
  bytes[bytes.size() / 2] ^= 0x10;
  store.overwrite(bytes);
  EXPECT_NE(store.read_error().find("corrupted"), std::string::npos) << store.read_error();
  EXPECT_NE(store.read_error().find("1_1_1.pieces"), std::string::npos) << "the message names the file";
}

TEST(NeuroglancerChunkStore, ForeignFileRefused) {
  const Store store("foreign");
  store.overwrite("solid ascii\nendsolid\n");
  EXPECT_NE(store.read_error().find("not a keymesh chunk-pieces file"), std::string::npos) << store.read_error();
}

TEST(NeuroglancerChunkStore, FileOfAnotherChunkRefused) {
  const Store store("moved");
  fs::copy_file(store.file, store.dir / "chunks" / "2_1_1.pieces");
  const std::string e = input_error([&] { ng::read_chunk_pieces(store.dir.string(), {2, 1, 1}); });
  EXPECT_NE(e.find("holds chunk 1 1 1"), std::string::npos) << e;
}

TEST(NeuroglancerChunkStore, TaskWithAnotherLayoutRefused) {
  const Store store("layout");
  auto other = store.layout;
  other.chunk_shape = {16, 8, 8};
  const std::string e = input_error([&] { ng::write_chunk_pieces(store.dir.string(), other, {0, 0, 0}, {}); });
  EXPECT_NE(e.find("chunk_shape [8,8,8]"), std::string::npos) << e;
  EXPECT_FALSE(fs::exists(store.dir / "chunks" / "0_0_0.pieces"));
  auto fewer_lods = store.layout;
  fewer_lods.lods = 2;
  const std::string f = input_error([&] { ng::assemble_multilod(store.dir.string(), fewer_lods, {}); });
  EXPECT_NE(f.find("lods 3"), std::string::npos) << f;
}

TEST(NeuroglancerChunkStore, AssemblyBeforeEveryTaskRanRefused) {
  const Store store("missing");
  const std::string e = input_error([&] { ng::assemble_multilod(store.dir.string(), store.layout, {}); });
  EXPECT_NE(e.find("0_0_0.pieces"), std::string::npos) << e;
  EXPECT_NE(e.find("has not run"), std::string::npos) << e;
  EXPECT_FALSE(fs::exists(store.dir / "info")) << "nothing written";
  const auto empty = neuroglancer_files::fresh_dir("no_tasks");
  const std::string f = input_error([&] { ng::assemble_multilod(empty.string(), store.layout, {}); });
  EXPECT_NE(f.find("no chunk task"), std::string::npos) << f;
}

TEST(NeuroglancerChunkStore, BadPiecesRefusedBeforeWriting) {
  const Store store("bad_pieces");
  auto pieces = neuroglancer_dataset::pieces(store.layout, neuroglancer_dataset::boxes());
  pieces.push_back(pieces.front());
  const auto dir = neuroglancer_files::fresh_dir("twice");
  EXPECT_NE(input_error([&] { ng::write_multilod(dir.string(), store.layout, pieces); }).find("given twice"), std::string::npos);
  pieces.pop_back();
  pieces[0].triangles[0] = 1u << 30;
  EXPECT_NE(input_error([&] { ng::write_multilod(dir.string(), store.layout, pieces); }).find("names point"), std::string::npos);
  EXPECT_NE(input_error([&] { ng::write_chunk_pieces(dir.string(), store.layout, {0, 0, 0}, {pieces[5]}); }), "")
      << "a piece of another chunk";
  EXPECT_TRUE(neuroglancer_files::output_files(dir).empty());
}

}  // namespace
