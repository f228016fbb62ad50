// The chunk tasks' route to the output equals the one-call write byte for
// byte: every chunk's pieces kept under DIR/chunks, then assembled; after an
// edit, re-assembling only the touched segments (--update) equals a full
// write of the edited pieces; and the bytes do not depend on the thread
// count or on the order of the pieces.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>

#include "io/neuroglancer_dataset.hpp"
#include "io/neuroglancer_test_files.hpp"
#include "keymesh/io/neuroglancer.hpp"
#include "keymesh/parallel/threads.hpp"

#include <sys/stat.h>

using namespace keymesh;
using namespace keymesh::tests;
namespace ng = keymesh::io::neuroglancer;
using Chunk = std::array<std::uint32_t, 3>;

namespace {

std::map<Chunk, std::vector<ng::ChunkPiece>> by_chunk(const ng::MultilodLayout& layout, const std::vector<ng::ChunkPiece>& pieces) {
  std::map<Chunk, std::vector<ng::ChunkPiece>> chunks;
  for (std::uint32_t z = 0; z < layout.chunks[2]; ++z)
    for (std::uint32_t y = 0; y < layout.chunks[1]; ++y)
      for (std::uint32_t x = 0; x < layout.chunks[0]; ++x) chunks[{x, y, z}];  // every chunk, empty ones too
  for (const auto& p : pieces) chunks[p.chunk].push_back(p);
  return chunks;
}

void run_chunk_tasks(const std::string& dir, const ng::MultilodLayout& layout, const std::vector<ng::ChunkPiece>& pieces) {
  for (const auto& [chunk, chunk_pieces] : by_chunk(layout, pieces)) ng::write_chunk_pieces(dir, layout, chunk, chunk_pieces);
}

// The synthetic boxes after an edit: box 2 grows, box 7 is removed.
std::vector<neuroglancer_dataset::Box> edited_boxes() {
  auto boxes = neuroglancer_dataset::boxes();
  boxes[1].hi = {15, 13, 14};
  boxes.pop_back();
  return boxes;
}

// A file's inode: a rewrite through AtomicFile (a rename) changes it.
ino_t inode(const std::filesystem::path& path) {
  struct stat st {};
  EXPECT_EQ(::stat(path.c_str(), &st), 0) << path;
  return st.st_ino;
}

bool same_piece(const ng::ChunkPiece& a, const ng::ChunkPiece& b) {
  return a.segment == b.segment && a.lod == b.lod && a.point_keys == b.point_keys && a.points == b.points &&
         a.triangles == b.triangles;
}

class NeuroglancerAssembly : public ::testing::TestWithParam<bool> {};  // parameter: sharded

TEST_P(NeuroglancerAssembly, ChunkTasksThenAssemblyEqualTheOneCallWrite) {
  const auto layout = neuroglancer_dataset::layout(GetParam());
  const auto pieces = neuroglancer_dataset::pieces(layout, neuroglancer_dataset::boxes());
  const ng::SegmentNames names{{1, "big box"}, {3, "tall box"}};
  const auto one_call = neuroglancer_files::fresh_dir("one_call"), tasks = neuroglancer_files::fresh_dir("tasks");
  ng::write_multilod(one_call.string(), layout, pieces, names);
  run_chunk_tasks(tasks.string(), layout, pieces);
  ng::assemble_multilod(tasks.string(), layout, {}, names);
  EXPECT_EQ(neuroglancer_files::output_difference(one_call, tasks), "");
  EXPECT_GE(neuroglancer_files::output_files(one_call).size(), GetParam() ? 3u : 10u);
  // read_chunk_pieces gives back what a task wrote.
  const auto chunks = by_chunk(layout, pieces);
  const auto back = ng::read_chunk_pieces(tasks.string(), {1, 1, 1});
  const auto& given = chunks.at({1, 1, 1});
  ASSERT_EQ(back.size(), given.size());
  for (std::size_t i = 0; i < back.size(); ++i) EXPECT_TRUE(same_piece(back[i], given[i]));
}

TEST_P(NeuroglancerAssembly, UpdateOfTouchedSegmentsEqualsAFullWrite) {
  const auto layout = neuroglancer_dataset::layout(GetParam());
  const auto before = neuroglancer_dataset::pieces(layout, neuroglancer_dataset::boxes());
  const auto after = neuroglancer_dataset::pieces(layout, edited_boxes());
  const auto updated = neuroglancer_files::fresh_dir("updated"), fresh = neuroglancer_files::fresh_dir("fresh");
  run_chunk_tasks(updated.string(), layout, before);
  ng::assemble_multilod(updated.string(), layout, {});
  // Rerun the tasks of the chunks whose pieces changed; the touched segments
  // are those of their old and new pieces.
  const auto old_chunks = by_chunk(layout, before), new_chunks = by_chunk(layout, after);
  std::set<std::uint64_t> touched;
  int rerun = 0;
  for (const auto& [chunk, now] : new_chunks) {
    const auto& was = old_chunks.at(chunk);
    const bool same = now.size() == was.size() && std::equal(now.begin(), now.end(), was.begin(), same_piece);
    if (same) continue;
    std::set<std::uint64_t> kept;
    for (const auto& p : ng::read_chunk_pieces(updated.string(), chunk)) kept.insert(p.segment);
    const auto listed = ng::kept_segments(updated.string(), chunk);
    EXPECT_EQ(std::vector<std::uint64_t>(kept.begin(), kept.end()), listed);
    touched.insert(listed.begin(), listed.end());
    for (const auto& p : now) touched.insert(p.segment);
    ng::write_chunk_pieces(updated.string(), layout, chunk, now);
    ++rerun;
  }
  // Segment 3 lies in chunks the edit leaves alone: an update that patches
  // (rather than rewrites everything) leaves its files alone.
  const auto untouched = updated / (GetParam() ? "0.shard" : "3.index");
  const ino_t untouched_inode = inode(untouched);
  ASSERT_GT(rerun, 0);
  EXPECT_TRUE(ng::kept_segments(fresh.string(), {0, 0, 0}).empty()) << "no task ran there";
  ASSERT_LT(rerun, 36) << "the edit touches some chunks, not all";
  EXPECT_TRUE(touched.count(7)) << "the removed segment is among the touched ones";
  EXPECT_FALSE(touched.count(3));
  ng::assemble_multilod(updated.string(), layout, {touched.begin(), touched.end()});
  ng::write_multilod(fresh.string(), layout, after);
  EXPECT_EQ(neuroglancer_files::output_difference(updated, fresh), "");
  if (!GetParam()) {
    EXPECT_FALSE(std::filesystem::exists(updated / "7.index")) << "segment 7's files removed";
    EXPECT_EQ(inode(untouched), untouched_inode) << "segment 3's manifest not rewritten";
  } else {
    EXPECT_NE(inode(untouched), untouched_inode) << "the one shard, holding touched segments, rebuilt";
  }
}

TEST_P(NeuroglancerAssembly, UpdateWithNewOptionsRewritesEverything) {
  // Names added since the last assembly: the info differs, so the update
  // cannot patch the old output and writes it whole.
  const auto layout = neuroglancer_dataset::layout(GetParam());
  const auto pieces = neuroglancer_dataset::pieces(layout, neuroglancer_dataset::boxes());
  const ng::SegmentNames names{{2, "small box"}};
  const auto updated = neuroglancer_files::fresh_dir("renamed"), fresh = neuroglancer_files::fresh_dir("named");
  run_chunk_tasks(updated.string(), layout, pieces);
  ng::assemble_multilod(updated.string(), layout, {});
  ng::assemble_multilod(updated.string(), layout, {2}, names);
  ng::write_multilod(fresh.string(), layout, pieces, names);
  EXPECT_EQ(neuroglancer_files::output_difference(updated, fresh), "");
}

TEST_P(NeuroglancerAssembly, BytesIndependentOfThreadsAndPieceOrder) {
  const auto layout = neuroglancer_dataset::layout(GetParam());
  auto pieces = neuroglancer_dataset::pieces(layout, neuroglancer_dataset::boxes());
  const auto one = neuroglancer_files::fresh_dir("threads1"), many = neuroglancer_files::fresh_dir("threads3");
  parallel::set_thread_count(1);
  ng::write_multilod(one.string(), layout, pieces);
  std::shuffle(pieces.begin(), pieces.end(), std::mt19937(7));
  parallel::set_thread_count(3);
  ng::write_multilod(many.string(), layout, pieces);
  parallel::set_thread_count(0);
  EXPECT_EQ(neuroglancer_files::output_difference(one, many), "");
}

INSTANTIATE_TEST_SUITE_P(Layouts, NeuroglancerAssembly, ::testing::Values(false, true),
                         [](const auto& test) { return test.param ? std::string("Sharded") : std::string("Unsharded"); });

TEST(NeuroglancerSharding, ManySegmentsFillSeveralShards) {
  auto layout = neuroglancer_dataset::layout(true);
  layout.lods = 2;
  const auto pieces = neuroglancer_dataset::pieces(layout, neuroglancer_dataset::many_boxes(600));
  const auto one_call = neuroglancer_files::fresh_dir("many"), tasks = neuroglancer_files::fresh_dir("many_tasks");
  ng::write_multilod(one_call.string(), layout, pieces);
  const auto files = neuroglancer_files::output_files(one_call);
  // 600 segments: 4 shards (2 bits, 150 a shard), 8 minishards each (3 bits).
  for (const char* shard : {"0.shard", "1.shard", "2.shard", "3.shard"}) EXPECT_TRUE(files.count(shard)) << shard;
  EXPECT_NE(files.at("info").find("\"shard_bits\": 2"), std::string::npos);
  EXPECT_NE(files.at("info").find("\"minishard_bits\": 3"), std::string::npos);
  run_chunk_tasks(tasks.string(), layout, pieces);
  ng::assemble_multilod(tasks.string(), layout, {});
  EXPECT_EQ(neuroglancer_files::output_difference(one_call, tasks), "");
  // --update of one segment rebuilds its shard only.
  std::map<std::string, ino_t> before;
  for (const char* shard : {"0.shard", "1.shard", "2.shard", "3.shard"}) before[shard] = inode(tasks / shard);
  ng::assemble_multilod(tasks.string(), layout, {pieces.front().segment});
  int rebuilt = 0;
  for (const auto& [shard, ino] : before) rebuilt += inode(tasks / shard) != ino;
  EXPECT_EQ(rebuilt, 1);
  EXPECT_EQ(neuroglancer_files::output_difference(one_call, tasks), "");
}

}  // namespace
