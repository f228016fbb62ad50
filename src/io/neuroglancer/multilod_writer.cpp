// The entry points of keymesh/io/neuroglancer.hpp: the one-call write, the
// chunk tasks' piece store, and the final step (whole or `--update`).
#include <filesystem>
#include <set>

#include "io/mesh_bytes.hpp"
#include "chunk_store.hpp"
#include "info_json.hpp"
#include "input_checks.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/io/atomic_file.hpp"
#include "keymesh/io/neuroglancer.hpp"
#include "keymesh/io/output_transaction.hpp"
#include "output_files.hpp"

namespace keymesh::io::neuroglancer {

namespace {

namespace fs = std::filesystem;

void write_file(const std::string& path, const std::string& bytes) {
  AtomicFile file(path);
  file.write(bytes);
  file.commit();
}

void check_chunk(const MultilodLayout& layout, const std::array<std::uint32_t, 3>& chunk) {
  for (int a = 0; a < 3; ++a)
    if (chunk[a] >= layout.chunks[a])
      throw InputError("neuroglancer: chunk (" + std::to_string(chunk[0]) + ", " + std::to_string(chunk[1]) + ", " +
                       std::to_string(chunk[2]) + ") is outside the grid of " + std::to_string(layout.chunks[0]) + " x " +
                       std::to_string(layout.chunks[1]) + " x " + std::to_string(layout.chunks[2]) + " chunks");
}

// The kept pieces of every chunk that `keep` accepts (all: an empty keep).
// Every chunk of the grid must have been written by its task.
std::vector<ChunkPiece> read_kept_pieces(const std::string& dir, const MultilodLayout& layout, const PieceFilter& keep) {
  std::vector<ChunkPiece> pieces;
  std::array<std::uint32_t, 3> c{};
  for (c[2] = 0; c[2] < layout.chunks[2]; ++c[2])
    for (c[1] = 0; c[1] < layout.chunks[1]; ++c[1])
      for (c[0] = 0; c[0] < layout.chunks[0]; ++c[0]) {
        const std::string path = chunk_pieces_path(dir, c);
        std::error_code ec;
        if (!fs::exists(path, ec))
          throw InputError(path + ": no such file (the task of chunk " + std::to_string(c[0]) + " " + std::to_string(c[1]) +
                           " " + std::to_string(c[2]) + " has not run)");
        for (ChunkPiece& piece : decode_chunk_pieces(path, c, keep)) {
          check_piece(layout, piece);
          pieces.push_back(std::move(piece));
        }
      }
  return pieces;
}

// The whole output from `pieces`.
void write_all(const std::string& dir, const MultilodLayout& layout, const std::vector<ChunkPiece>& pieces,
               const SegmentNames& names) {
  const std::vector<SegmentFiles> files = encode_segments(layout, pieces_by_segment(pieces));
  write_output(dir, layout, files, names, sharding_of(layout, files.size()), OutputScope{});
}

bool info_is(const std::string& dir, const std::string& expected) {
  const fs::path path = fs::path(dir) / "info";
  std::error_code ec;
  return fs::is_regular_file(path, ec) && mesh_bytes::read_whole_file(path.string()).view() == expected;
}

// `--update`: only `segments`' files, or the shards holding them, rewritten;
// the whole output when the existing one was written with other options
// (another info: sharding, quantization, names) and so cannot be patched.
void update(const std::string& dir, const MultilodLayout& layout, const std::vector<std::uint64_t>& segments,
            const SegmentNames& names) {
  const std::set<std::uint64_t> chosen(segments.begin(), segments.end());
  std::optional<ShardingSpec> sharding;
  PieceFilter keep = [&](std::uint64_t segment, std::uint64_t) { return chosen.count(segment) != 0; };
  OutputScope scope{false, segments, {}};
  if (layout.sharded) {
    std::set<std::uint64_t> meshed;  // the full run's segment count decides its sharding
    read_kept_pieces(dir, layout, [&](std::uint64_t segment, std::uint64_t triangles) {
      if (triangles != 0) meshed.insert(segment);
      return false;
    });
    sharding = sharding_for(meshed.size());
    std::set<std::uint64_t> shards;
    for (std::uint64_t s : chosen) shards.insert(shard_of(*sharding, s));
    scope = OutputScope{false, {}, {shards.begin(), shards.end()}};
    keep = [&, shards](std::uint64_t segment, std::uint64_t) { return shards.count(shard_of(*sharding, segment)) != 0; };
  }
  if (!info_is(dir, info_json(layout, sharding, !names.empty()))) {
    write_all(dir, layout, read_kept_pieces(dir, layout, {}), names);
    return;
  }
  const std::vector<ChunkPiece> pieces = read_kept_pieces(dir, layout, keep);
  write_output(dir, layout, encode_segments(layout, pieces_by_segment(pieces)), names, sharding, scope);
}

}  // namespace

void write_multilod(const std::string& dir, const MultilodLayout& layout, const std::vector<ChunkPiece>& pieces,
                    const SegmentNames& names) {
  check_layout(layout);
  for (const ChunkPiece& piece : pieces) check_piece(layout, piece);
  OutputTransaction outputs;
  write_all(dir, layout, pieces, names);
  outputs.commit();
}

void write_chunk_pieces(const std::string& dir, const MultilodLayout& layout, const std::array<std::uint32_t, 3>& chunk,
                        const std::vector<ChunkPiece>& pieces) {
  check_layout(layout);
  check_chunk(layout, chunk);
  for (const ChunkPiece& piece : pieces) {
    check_piece(layout, piece);
    if (piece.chunk != chunk) throw InputError("neuroglancer: a piece of another chunk given with chunk " + std::to_string(chunk[0]) + " " +
                                               std::to_string(chunk[1]) + " " + std::to_string(chunk[2]));
  }
  pieces_by_segment(pieces);  // refuses a piece given twice
  OutputTransaction outputs;
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "chunks", ec);
  if (ec) throw InputError((fs::path(dir) / "chunks").string() + ": cannot create it: " + ec.message());
  if (fs::exists(layout_record_path(dir), ec))
    check_layout_record(dir, layout);
  else
    write_file(layout_record_path(dir), layout_record(layout));
  write_file(chunk_pieces_path(dir, chunk), encode_chunk_pieces(chunk, pieces));
  outputs.commit();
}

std::vector<ChunkPiece> read_chunk_pieces(const std::string& dir, const std::array<std::uint32_t, 3>& chunk) {
  return decode_chunk_pieces(chunk_pieces_path(dir, chunk), chunk);
}

std::vector<std::uint64_t> kept_segments(const std::string& dir, const std::array<std::uint32_t, 3>& chunk) {
  const std::string path = chunk_pieces_path(dir, chunk);
  std::error_code ec;
  if (!fs::exists(path, ec)) return {};
  std::set<std::uint64_t> segments;
  decode_chunk_pieces(path, chunk, [&](std::uint64_t segment, std::uint64_t) {
    segments.insert(segment);
    return false;
  });
  return {segments.begin(), segments.end()};
}

void assemble_multilod(const std::string& dir, const MultilodLayout& layout, const std::vector<std::uint64_t>& segments,
                       const SegmentNames& names) {
  check_layout(layout);
  check_layout_record(dir, layout);
  OutputTransaction outputs;
  if (segments.empty())
    write_all(dir, layout, read_kept_pieces(dir, layout, {}), names);
  else
    update(dir, layout, segments, names);
  outputs.commit();
}

}  // namespace keymesh::io::neuroglancer
