#pragma once
// zlib's own compress2 of a test's bytes (level 6): what the readers of
// zlib-compressed .vti/.vtu blocks and Zarr chunks must inflate, made
// without the library's code; and zlib's gzip member of them (gzip NRRD and
// NIfTI).
#include <gtest/gtest.h>
#include <zlib.h>

#include <string>

inline std::string zlib_bytes(const std::string& data) {
  uLongf n = compressBound(data.size());
  std::string out(n, '\0');
  EXPECT_EQ(compress2(reinterpret_cast<Bytef*>(out.data()), &n, reinterpret_cast<const Bytef*>(data.data()),
                      data.size(), 6),
            Z_OK);
  out.resize(n);
  return out;
}

inline std::string gzip_bytes(const std::string& data) {
  z_stream z{};
  EXPECT_EQ(deflateInit2(&z, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY), Z_OK);  // 15 + 16: gzip wrapper
  std::string out(deflateBound(&z, data.size()) + 64, '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  z.avail_in = static_cast<uInt>(data.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  EXPECT_EQ(deflate(&z, Z_FINISH), Z_STREAM_END);
  out.resize(z.total_out);
  deflateEnd(&z);
  return out;
}
