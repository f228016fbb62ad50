#include "sharding.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <memory>
#include <stdexcept>

#include <libdeflate.h>

#include "murmurhash3.hpp"

namespace keymesh::io::neuroglancer {

namespace {

constexpr std::size_t kSegmentsPerShard = 256;
constexpr std::size_t kSegmentsPerMinishard = 32;

int ceil_log2(std::size_t n) { return n <= 1 ? 0 : static_cast<int>(std::bit_width(n - 1)); }

std::size_t ceil_div(std::size_t a, std::size_t b) { return (a + b - 1) / b; }

std::uint64_t low_bits(std::uint64_t value, int bits) { return bits >= 64 ? value : value & ((std::uint64_t{1} << bits) - 1); }

std::uint64_t hashed(const ShardingSpec& spec, std::uint64_t segment) {
  return sharding_hash(spec.preshift_bits >= 64 ? 0 : segment >> spec.preshift_bits);
}

std::uint64_t minishard_of(const ShardingSpec& spec, std::uint64_t segment) {
  return low_bits(hashed(spec, segment), spec.minishard_bits);
}

void put_u64(std::string& out, std::uint64_t value) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>(value >> (8 * i)));
}

std::string gzip(const std::string& raw) {
  std::unique_ptr<libdeflate_compressor, decltype(&libdeflate_free_compressor)> compressor(
      libdeflate_alloc_compressor(6), libdeflate_free_compressor);
  if (!compressor) throw std::bad_alloc();
  std::string out(libdeflate_gzip_compress_bound(compressor.get(), raw.size()), '\0');
  const std::size_t n = libdeflate_gzip_compress(compressor.get(), raw.data(), raw.size(), out.data(), out.size());
  if (n == 0) throw std::runtime_error("neuroglancer: gzip of a minishard index failed");
  out.resize(n);
  return out;
}

// One minishard's index: ids, starts and sizes, each row delta encoded.
std::string minishard_index(const std::vector<std::array<std::uint64_t, 3>>& entries /* id, start, size */) {
  std::string raw;
  std::uint64_t previous_id = 0;
  for (const auto& e : entries) put_u64(raw, e[0] - previous_id), previous_id = e[0];
  std::uint64_t previous_end = 0;
  for (const auto& e : entries) put_u64(raw, e[1] - previous_end), previous_end = e[1] + e[2];
  for (const auto& e : entries) put_u64(raw, e[2]);
  return gzip(raw);
}

}  // namespace

ShardingSpec sharding_for(std::size_t segments) {
  ShardingSpec spec;
  spec.shard_bits = ceil_log2(ceil_div(segments, kSegmentsPerShard));
  const std::size_t per_shard = ceil_div(segments, std::size_t{1} << spec.shard_bits);
  spec.minishard_bits = ceil_log2(ceil_div(per_shard, kSegmentsPerMinishard));
  return spec;
}

std::uint64_t shard_of(const ShardingSpec& spec, std::uint64_t segment) {
  return low_bits(hashed(spec, segment) >> spec.minishard_bits, spec.shard_bits);
}

std::string shard_file_name(const ShardingSpec& spec, std::uint64_t shard) {
  static const char* const kHex = "0123456789abcdef";
  std::string digits;
  do digits.insert(digits.begin(), kHex[shard & 15]), shard >>= 4;
  while (shard != 0);
  const std::size_t width = static_cast<std::size_t>(spec.shard_bits + 3) / 4;
  if (digits.size() < width) digits.insert(0, width - digits.size(), '0');
  return digits + ".shard";
}

std::string shard_bytes(const ShardingSpec& spec, std::vector<const SegmentFiles*> segments) {
  std::sort(segments.begin(), segments.end(), [&](const SegmentFiles* a, const SegmentFiles* b) {
    const std::uint64_t ma = minishard_of(spec, a->segment), mb = minishard_of(spec, b->segment);
    return ma != mb ? ma < mb : a->segment < b->segment;
  });
  const std::size_t minishards = std::size_t{1} << spec.minishard_bits;
  std::vector<std::vector<std::array<std::uint64_t, 3>>> entries(minishards);
  std::string body;  // everything after the shard index
  for (const SegmentFiles* s : segments) {
    body += s->data;
    entries[minishard_of(spec, s->segment)].push_back({s->segment, body.size(), s->manifest.size()});
    body += s->manifest;
  }
  std::string index;
  for (const auto& minishard : entries) {
    const std::uint64_t start = body.size();
    if (!minishard.empty()) body += minishard_index(minishard);
    put_u64(index, start);
    put_u64(index, body.size());
  }
  return index + body;
}

}  // namespace keymesh::io::neuroglancer
