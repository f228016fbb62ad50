#include "chunk_store.hpp"

#include <libdeflate.h>

#include <bit>
#include <cstring>
#include <filesystem>
#include <sstream>

#include <nlohmann/json.hpp>

#include "io/mesh_bytes.hpp"
#include "keymesh/core/error.hpp"

namespace keymesh::io::neuroglancer {

namespace {

static_assert(std::endian::native == std::endian::little, "chunk pieces are stored as the host's little-endian words");

constexpr char kMagic[8] = {'K', 'M', 'N', 'G', 'P', 'C', 'S', '1'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kHeaderBytes = 8 + 4 + 12 + 8 + 8 + 4;

template <class T>
void put(std::string& out, const T* values, std::size_t n) {
  out.append(reinterpret_cast<const char*>(values), n * sizeof(T));
}
template <class T>
void put(std::string& out, T value) {
  put(out, &value, 1);
}

// The payload's CRC-32 (gzip's polynomial: zlib's crc32 gives the same
// value). libdeflate's folds with carry-less multiplies, about 10 times
// fewer instructions than zlib's: the one-call run checksums every chunk's
// pieces (48 MB for AAL at 3 levels) on one thread.
std::uint32_t crc(const char* data, std::size_t size) { return libdeflate_crc32(0, data, size); }

// Reads the container's fields in order, refusing to pass its end.
class Reader {
 public:
  Reader(const std::string& path, std::string_view bytes) : path_(path), bytes_(bytes) {}
  template <class T>
  T get() {
    T value;
    std::memcpy(&value, take(sizeof(T), 1), sizeof(T));
    return value;
  }
  template <class T>
  void get(std::vector<T>& out, std::uint64_t n) {
    const char* p = take(sizeof(T), n);
    out.resize(static_cast<std::size_t>(n));
    if (n != 0) std::memcpy(out.data(), p, static_cast<std::size_t>(n) * sizeof(T));
  }
  void skip(std::size_t size, std::uint64_t n) { take(size, n); }
  std::size_t left() const { return bytes_.size() - at_; }
  [[noreturn]] void fail(const std::string& why) const { throw InputError(path_ + ": " + why); }

 private:
  const char* take(std::size_t size, std::uint64_t n) {
    if (n > left() / size) fail("truncated: a piece needs more bytes than the file holds");
    const char* p = bytes_.data() + at_;
    at_ += static_cast<std::size_t>(n) * size;
    return p;
  }
  std::string path_;
  std::string_view bytes_;
  std::size_t at_ = 0;
};

// The header's checks; returns the piece count.
std::uint64_t read_header(Reader& in, const std::array<std::uint32_t, 3>& chunk, std::string_view bytes) {
  if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    in.fail("not a keymesh chunk-pieces file (no KMNGPCS1 header)");
  in.skip(1, sizeof kMagic);
  if (const auto version = in.get<std::uint32_t>(); version != kVersion)
    in.fail("chunk-pieces version " + std::to_string(version) + " (this keymesh reads " + std::to_string(kVersion) + ")");
  std::array<std::uint32_t, 3> stored{};
  for (auto& c : stored) c = in.get<std::uint32_t>();
  if (stored != chunk)
    in.fail("holds chunk " + std::to_string(stored[0]) + " " + std::to_string(stored[1]) + " " + std::to_string(stored[2]) +
            ", not the chunk its name says");
  const auto pieces = in.get<std::uint64_t>();
  const auto payload = in.get<std::uint64_t>();
  const auto checksum = in.get<std::uint32_t>();
  if (payload != in.left())
    in.fail("truncated or padded: the header declares " + std::to_string(payload) + " payload bytes, the file holds " +
            std::to_string(in.left()));
  if (crc(bytes.data() + kHeaderBytes, in.left()) != checksum) in.fail("corrupted: its payload's CRC-32 does not match");
  return pieces;
}

ChunkPiece read_piece(Reader& in, const std::array<std::uint32_t, 3>& chunk, std::uint64_t points, std::uint64_t triangles) {
  ChunkPiece piece;
  piece.chunk = chunk;
  in.get(piece.point_keys, points);
  in.get(piece.points, 3 * points);
  in.get(piece.triangles, 3 * triangles);
  for (std::uint32_t corner : piece.triangles)
    if (corner >= points) in.fail("corrupted: a triangle names point " + std::to_string(corner) + " of " + std::to_string(points));
  return piece;
}

}  // namespace

std::string chunk_pieces_path(const std::string& dir, const std::array<std::uint32_t, 3>& chunk) {
  return (std::filesystem::path(dir) / "chunks" /
          (std::to_string(chunk[0]) + "_" + std::to_string(chunk[1]) + "_" + std::to_string(chunk[2]) + ".pieces"))
      .string();
}

std::string layout_record_path(const std::string& dir) { return (std::filesystem::path(dir) / "chunks" / "layout.json").string(); }

std::string encode_chunk_pieces(const std::array<std::uint32_t, 3>& chunk, const std::vector<const ChunkPiece*>& pieces) {
  std::size_t bytes = 0;  // the payload's size: grown once, not by doubling
  for (const ChunkPiece* p : pieces)
    bytes += 8 + 4 + 8 + 8 + 8 * p->point_keys.size() + 4 * p->points.size() + 4 * p->triangles.size();
  // The header, its last two fields (payload size, checksum) filled in once
  // the payload follows it in the same string (no second copy of the payload).
  std::string out(kMagic, sizeof kMagic);
  out.reserve(kHeaderBytes + bytes);
  put(out, kVersion);
  put(out, chunk.data(), 3);
  put<std::uint64_t>(out, pieces.size());
  put<std::uint64_t>(out, 0);
  put<std::uint32_t>(out, 0);
  for (const ChunkPiece* p : pieces) {
    put(out, p->segment);
    put(out, p->lod);
    put<std::uint64_t>(out, p->point_keys.size());
    put<std::uint64_t>(out, p->triangles.size() / 3);
    put(out, p->point_keys.data(), p->point_keys.size());
    put(out, p->points.data(), p->points.size());
    put(out, p->triangles.data(), p->triangles.size());
  }
  const std::uint64_t payload = out.size() - kHeaderBytes;
  const std::uint32_t checksum = crc(out.data() + kHeaderBytes, payload);
  std::memcpy(out.data() + kHeaderBytes - sizeof checksum - sizeof payload, &payload, sizeof payload);
  std::memcpy(out.data() + kHeaderBytes - sizeof checksum, &checksum, sizeof checksum);
  return out;
}

std::vector<ChunkPiece> decode_chunk_pieces(const std::string& path, const std::array<std::uint32_t, 3>& chunk,
                                            const PieceFilter& keep) {
  const mesh_bytes::FileBytes bytes = mesh_bytes::read_whole_file(path);
  Reader in(path, bytes.view());
  const std::uint64_t count = read_header(in, chunk, bytes.view());
  std::vector<ChunkPiece> pieces;
  for (std::uint64_t i = 0; i < count; ++i) {
    const auto segment = in.get<std::uint64_t>();
    const auto lod = in.get<std::uint32_t>();
    const auto points = in.get<std::uint64_t>();
    const auto triangles = in.get<std::uint64_t>();
    if (keep && !keep(segment, triangles)) {
      in.skip(8 + 12, points);
      in.skip(12, triangles);
      continue;
    }
    pieces.push_back(read_piece(in, chunk, points, triangles));
    pieces.back().segment = segment;
    pieces.back().lod = lod;
  }
  if (in.left() != 0) in.fail("corrupted: " + std::to_string(in.left()) + " bytes after the last piece");
  return pieces;
}

}  // namespace keymesh::io::neuroglancer
