// detail::inflate_gzip_file, inflate_zlib_exact and inflate_zlib_or_gzip_exact
// (src/io/whole_inflate.cpp):
// gzip members and zlib streams made by zlib's deflate from bytes the test
// chose, inflated by libdeflate. What they give must be those bytes; what
// they leave to zlib (std::nullopt, false) is every case that is not clean,
// so that the readers' zlib path decides it.
// tests/cli/test_gzip_volumes_cli.py checks the readers end to end.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "io/whole_inflate.hpp"
#include "zlib_bytes.hpp"

namespace keymesh::io {
namespace {

namespace fs = std::filesystem;

std::string noise(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::string s(n, '\0');
  for (char& c : s) c = static_cast<char>(rng() % 7);  // compressible, not trivially
  return s;
}

class WholeInflate : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = (fs::temp_directory_path() / ("keymesh-whole-inflate-" + std::to_string(::getpid()) + "-" +
                                          ::testing::UnitTest::GetInstance()->current_test_info()->name()))
                .string();
  }
  void TearDown() override { fs::remove(path_); }

  // The file holding `bytes`, inflated from `offset` with `skip` and `size`.
  std::optional<std::string> inflate(const std::string& bytes, std::uint64_t offset, std::uint64_t skip,
                                     std::uint64_t size) {
    std::ofstream(path_, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    const auto out = detail::inflate_gzip_file(path_, offset, skip, size);
    if (!out) return std::nullopt;
    return std::string(reinterpret_cast<const char*>(out->data()), out->size());
  }

  std::string path_;
};

TEST_F(WholeInflate, OneMemberAfterAnOffsetWithItsFirstBytesDropped) {
  const std::string data = noise(100000, 1), head = "NRRD0004\nheader text\n\n";
  EXPECT_EQ(inflate(head + gzip_bytes(data), head.size(), 1000, 99000), data.substr(1000));
  EXPECT_EQ(inflate(gzip_bytes(data), 0, 0, data.size()), data);
}

TEST_F(WholeInflate, MembersOneAfterAnother) {
  // An empty member, a one-byte one, and a first member that inflates far
  // past the first allocation (its 300 kB of zeros compress ~1000:1), so
  // the buffer doubles under it; the last member's trailer does not give
  // the whole length.
  const std::string a(300000, '\0'), b = "x", c = noise(5000, 2);
  const std::string file = gzip_bytes(a) + gzip_bytes("") + gzip_bytes(b) + gzip_bytes(c);
  EXPECT_EQ(inflate(file, 0, 0, a.size() + b.size() + c.size()), a + b + c);
  EXPECT_EQ(inflate(file, 0, 299990, 10 + b.size() + c.size()), a.substr(299990) + b + c);
}

TEST_F(WholeInflate, MembersAfterTheDeclaredEndAreNotLookedAt) {
  const std::string a = noise(4000, 3), b = noise(3000, 4);
  EXPECT_EQ(inflate(gzip_bytes(a) + gzip_bytes(b) + "not gzip", 0, 0, a.size() + b.size()), a + b);
  EXPECT_EQ(inflate(gzip_bytes(a) + "not gzip", 0, 0, a.size()), a);
}

TEST_F(WholeInflate, WhatIsNotCleanIsLeftToZlib) {
  const std::string a = noise(4000, 5), b = noise(3000, 6);
  const std::string ga = gzip_bytes(a), gb = gzip_bytes(b);
  const std::size_t n = a.size() + b.size();
  EXPECT_EQ(inflate(a + b, 0, 0, n), std::nullopt) << "not gzip";
  EXPECT_EQ(inflate(ga + gb, 0, 0, n + 1), std::nullopt) << "one byte short";
  EXPECT_EQ(inflate(ga + gb, 0, 0, n - 1), std::nullopt) << "the last member longer than declared";
  EXPECT_EQ(inflate(ga + "junk" + gb, 0, 0, n), std::nullopt) << "junk between members";
  EXPECT_EQ(inflate(ga + gb.substr(0, gb.size() - 1), 0, 0, n), std::nullopt) << "truncated";
  EXPECT_EQ(inflate(ga + gb, ga.size() + gb.size(), 0, 1), std::nullopt) << "nothing after the offset";
  std::string bad_crc = ga + gb;
  bad_crc[ga.size() + gb.size() - 8] ^= 1;  // the CRC-32, first of the trailer's 8 bytes
  EXPECT_EQ(inflate(bad_crc, 0, 0, n), std::nullopt) << "CRC-32";
  std::string bad_length = ga + gb;
  bad_length[ga.size() - 4] ^= 1;  // the first member's ISIZE
  EXPECT_EQ(inflate(bad_length, 0, 0, n), std::nullopt) << "length";
  std::string bad_data = ga + gb;
  bad_data[20] ^= 0x55;
  EXPECT_EQ(inflate(bad_data, 0, 0, n), std::nullopt) << "deflate data";
  // A header CRC-16 (FHCRC), even a right one: libdeflate would skip it.
  std::string with_hcrc = gb.substr(0, 10);
  with_hcrc[3] = static_cast<char>(with_hcrc[3] | 0x02);
  const auto crc = static_cast<std::uint32_t>(crc32(0, reinterpret_cast<const Bytef*>(with_hcrc.data()), 10));
  with_hcrc += std::string{static_cast<char>(crc & 0xff), static_cast<char>((crc >> 8) & 0xff)} + gb.substr(10);
  EXPECT_EQ(inflate(ga + with_hcrc, 0, 0, n), std::nullopt) << "header CRC";
}

// inflate_zlib_exact on `stream`, into exactly `expected` bytes.
std::optional<std::string> inflate_zlib(const std::string& stream, std::size_t expected) {
  std::string out(expected, '\0');
  if (!detail::inflate_zlib_exact(stream.data(), stream.size(), out.data(), expected)) return std::nullopt;
  return out;
}

TEST(WholeInflateZlib, ExactlyTheDeclaredBytesOfAWellFormedStream) {
  const std::string a = noise(40000, 7), z = zlib_bytes(a);
  EXPECT_EQ(inflate_zlib(z, a.size()), a);
  EXPECT_EQ(inflate_zlib(z + "bytes after the stream", a.size()), a);
  EXPECT_EQ(inflate_zlib(zlib_bytes(""), 0), "");
  EXPECT_EQ(inflate_zlib(z, a.size() + 1), std::nullopt) << "inflates to fewer";
  EXPECT_EQ(inflate_zlib(z, a.size() - 1), std::nullopt) << "inflates to more";
  EXPECT_EQ(inflate_zlib(z.substr(0, z.size() - 1), a.size()), std::nullopt) << "truncated";
  std::string bad_adler = z;
  bad_adler.back() = static_cast<char>(bad_adler.back() ^ 1);
  EXPECT_EQ(inflate_zlib(bad_adler, a.size()), std::nullopt) << "Adler-32";
  std::string dictionary = z;  // FDICT set, FCHECK adjusted to keep the header a multiple of 31
  dictionary[1] = static_cast<char>(dictionary[1] | 0x20);
  dictionary[1] = static_cast<char>((dictionary[1] & 0xe0) + (31 - ((static_cast<unsigned char>(dictionary[0]) << 8 |
                                                                   (dictionary[1] & 0xe0)) % 31)) % 31);
  EXPECT_EQ(inflate_zlib(dictionary, a.size()), std::nullopt) << "preset dictionary";
}

TEST(WholeInflateZlib, ZlibOrOneGzipMemberAsZlibDetectsThem) {
  const std::string a = noise(30000, 8), b = noise(100, 9);
  std::string out(a.size(), '\0');
  auto inflate_either = [&](const std::string& s) {
    return detail::inflate_zlib_or_gzip_exact(s.data(), s.size(), out.data(), out.size()) && out == a;
  };
  EXPECT_TRUE(inflate_either(zlib_bytes(a)));
  EXPECT_TRUE(inflate_either(gzip_bytes(a)));
  EXPECT_TRUE(inflate_either(gzip_bytes(a) + "after the member"));
  // zlib's inflate stops at the end of the first member.
  EXPECT_FALSE(inflate_either(gzip_bytes(a.substr(0, 1000)) + gzip_bytes(a.substr(1000))));
  std::string hcrc = gzip_bytes(a);
  hcrc[3] = static_cast<char>(hcrc[3] | 0x02);
  EXPECT_FALSE(inflate_either(hcrc.substr(0, 10) + "\x01\x02" + hcrc.substr(10))) << "header CRC";
  EXPECT_FALSE(inflate_either(gzip_bytes(a + b))) << "longer";
  EXPECT_FALSE(inflate_either(a)) << "neither";
}

}  // namespace
}  // namespace keymesh::io
