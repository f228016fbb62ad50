// The entry points of keymesh/io/neuroglancer.hpp: the one-call write (with
// its chunk store: neuroglancer_runs.hpp), the chunk tasks' piece store, and
// the final step (whole or `--update`).
#include <exception>
#include <filesystem>
#include <functional>
#include <map>
#include <set>

#include "io/mesh_bytes.hpp"
#include "chunk_store.hpp"
#include "info_json.hpp"
#include "input_checks.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/io/atomic_file.hpp"
#include "keymesh/io/neuroglancer.hpp"
#include "keymesh/io/neuroglancer_runs.hpp"
#include "keymesh/io/output_transaction.hpp"
#include "keymesh/parallel/for_each_task.hpp"
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

// A chunk's kept pieces as this command sees them: the file it wrote itself
// (staged until the command commits: --update re-runs chunks, then
// assembles), else the one on disk.
std::string kept_pieces_path(const std::string& dir, const std::array<std::uint32_t, 3>& chunk) {
  const std::string path = chunk_pieces_path(dir, chunk);
  const OutputTransaction* command = OutputTransaction::current();
  return command ? command->readable(path) : path;
}

// The kept pieces of every chunk that `keep` accepts (all: an empty keep).
// Every chunk of the grid must have been written by its task.
std::vector<ChunkPiece> read_kept_pieces(const std::string& dir, const MultilodLayout& layout, const PieceFilter& keep) {
  std::vector<ChunkPiece> pieces;
  std::array<std::uint32_t, 3> c{};
  for (c[2] = 0; c[2] < layout.chunks[2]; ++c[2])
    for (c[1] = 0; c[1] < layout.chunks[1]; ++c[1])
      for (c[0] = 0; c[0] < layout.chunks[0]; ++c[0]) {
        const std::string path = kept_pieces_path(dir, c);
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

// The pieces' checks, in parallel: the first bad piece's error whatever the
// thread count.
void check_pieces(const MultilodLayout& layout, const std::vector<ChunkPiece>& pieces) {
  parallel::for_each_task(static_cast<Id>(pieces.size()), [&](Id i) { check_piece(layout, pieces[i]); });
}

// The whole output from `pieces`; `beside` (encode_segments) runs on this
// thread while the segments are encoded, its error kept to be thrown after
// the output's own.
void write_all(const std::string& dir, const MultilodLayout& layout, const std::vector<ChunkPiece>& pieces,
               const SegmentNames& names, const std::function<void()>& beside = {}) {
  std::exception_ptr beside_error;
  const std::vector<SegmentFiles> files = encode_segments(layout, pieces_by_segment(pieces), [&] {
    try {
      if (beside) beside();
    } catch (...) {
      beside_error = std::current_exception();
    }
  });
  write_output(dir, layout, files, names, sharding_of(layout, files.size()), OutputScope{});
  if (beside_error) std::rethrow_exception(beside_error);
}

// A checked chunk's pieces kept: the layout record (once per command) and
// the chunk's file, staged in the caller's transaction.
void keep_chunk_pieces(const std::string& dir, const MultilodLayout& layout, const std::array<std::uint32_t, 3>& chunk,
                       const std::vector<const ChunkPiece*>& pieces) {
  OutputTransaction outputs;
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "chunks", ec);
  if (ec) throw InputError((fs::path(dir) / "chunks").string() + ": cannot create it: " + ec.message());
  // One command may keep several chunks (the one-call run and --update keep
  // theirs): the record it staged reaches the disk only when it commits.
  const OutputTransaction* command = OutputTransaction::current();
  if (fs::exists(layout_record_path(dir), ec))
    check_layout_record(dir, layout);
  else if (!(command && command->staged(layout_record_path(dir))))
    write_file(layout_record_path(dir), layout_record(layout));
  write_file(chunk_pieces_path(dir, chunk), encode_chunk_pieces(chunk, pieces));
  outputs.commit();
}

// Every chunk's checked pieces kept, empty chunks too: the store is complete.
// Each chunk's pieces in the order `pieces` holds them.
void keep_every_chunk(const std::string& dir, const MultilodLayout& layout, const std::vector<ChunkPiece>& pieces) {
  std::map<std::array<std::uint32_t, 3>, std::vector<const ChunkPiece*>> chunks;
  for (const ChunkPiece& p : pieces) chunks[p.chunk].push_back(&p);
  const std::vector<const ChunkPiece*> none;
  for (std::uint32_t z = 0; z < layout.chunks[2]; ++z)
    for (std::uint32_t y = 0; y < layout.chunks[1]; ++y)
      for (std::uint32_t x = 0; x < layout.chunks[0]; ++x) {
        const auto at = chunks.find({x, y, z});
        keep_chunk_pieces(dir, layout, {x, y, z}, at == chunks.end() ? none : at->second);
      }
}

// The pieces' memory per triangle, for batching: a triangle's three corners
// (12 bytes) and about half a point (12 bytes of position, 8 of key), with
// room for the vectors' slack and the segment's encoding.
constexpr std::uint64_t kPieceBytesPerTriangle = 48;

// The final step in batches of about `batch_bytes` of pieces: a first pass
// over the chunk files counts each segment's triangles (no points decoded),
// then each batch of segments (of whole shards when sharded, in increasing
// order) is read, encoded and written. Each file depends only on its own
// segment or shard, so the bytes are write_all's.
std::size_t write_all_in_batches(const std::string& dir, const MultilodLayout& layout, const SegmentNames& names,
                                 std::uint64_t batch_bytes) {
  std::map<std::uint64_t, std::uint64_t> triangles;  // meshed segments
  read_kept_pieces(dir, layout, [&](std::uint64_t segment, std::uint64_t n) {
    if (n != 0) triangles[segment] += n;
    return false;
  });
  const std::optional<ShardingSpec> sharding = sharding_of(layout, triangles.size());
  // Batch units: a segment, or a shard's segments.
  std::map<std::uint64_t, std::pair<std::vector<std::uint64_t>, std::uint64_t>> units;
  for (const auto& [segment, n] : triangles) {
    auto& unit = units[sharding ? shard_of(*sharding, segment) : segment];
    unit.first.push_back(segment);
    unit.second += n * kPieceBytesPerTriangle;
  }
  OutputParts parts(dir, layout, names, sharding);
  std::size_t batches = 0;
  auto flush = [&](std::set<std::uint64_t>& batch) {
    if (batch.empty()) return;
    ++batches;
    const std::vector<ChunkPiece> pieces =
        read_kept_pieces(dir, layout, [&](std::uint64_t segment, std::uint64_t) { return batch.count(segment) != 0; });
    parts.add(encode_segments(layout, pieces_by_segment(pieces)));
    batch.clear();
  };
  std::set<std::uint64_t> batch;
  std::uint64_t held = 0;
  for (const auto& [key, unit] : units) {
    if (!batch.empty() && held + unit.second > batch_bytes) flush(batch), held = 0;
    batch.insert(unit.first.begin(), unit.first.end());
    held += unit.second;
  }
  flush(batch);
  parts.finish();
  return batches;
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
  check_pieces(layout, pieces);
  OutputTransaction outputs;
  write_all(dir, layout, pieces, names);
  outputs.commit();
}

void write_multilod_and_chunks(const std::string& dir, const MultilodLayout& layout, std::vector<ChunkPiece>&& pieces,
                               const SegmentNames& names) {
  check_layout(layout);
  check_pieces(layout, pieces);
  OutputTransaction outputs;  // inside the CLI's own: its files join the command's
  // The chunk store is written on this thread while the other threads encode
  // the segments (it needs none of their results); its error, if any, comes
  // after the output's, as when it was written after the output.
  write_all(dir, layout, pieces, names, [&] { keep_every_chunk(dir, layout, pieces); });
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
  std::vector<const ChunkPiece*> kept;
  for (const ChunkPiece& piece : pieces) kept.push_back(&piece);
  keep_chunk_pieces(dir, layout, chunk, kept);
}

std::vector<ChunkPiece> read_chunk_pieces(const std::string& dir, const std::array<std::uint32_t, 3>& chunk) {
  return decode_chunk_pieces(kept_pieces_path(dir, chunk), chunk);
}

std::vector<std::uint64_t> kept_segments(const std::string& dir, const std::array<std::uint32_t, 3>& chunk) {
  const std::string path = kept_pieces_path(dir, chunk);
  std::error_code ec;
  if (!fs::exists(path, ec)) return {};
  std::set<std::uint64_t> segments;
  decode_chunk_pieces(path, chunk, [&](std::uint64_t segment, std::uint64_t) {
    segments.insert(segment);
    return false;
  });
  return {segments.begin(), segments.end()};
}

std::size_t assemble_multilod(const std::string& dir, const MultilodLayout& layout,
                              const std::vector<std::uint64_t>& segments, const SegmentNames& names,
                              std::uint64_t batch_bytes) {
  check_layout(layout);
  check_layout_record(dir, layout);
  OutputTransaction outputs;
  std::size_t batches = 1;
  if (segments.empty() && batch_bytes != 0)
    batches = write_all_in_batches(dir, layout, names, batch_bytes);
  else if (segments.empty())
    write_all(dir, layout, read_kept_pieces(dir, layout, {}), names);
  else
    update(dir, layout, segments, names);
  outputs.commit();
  return batches;
}

}  // namespace keymesh::io::neuroglancer
