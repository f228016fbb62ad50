#pragma once
// zlib's own compress2 of a test's bytes (level 6): what the readers of
// zlib-compressed .vti/.vtu blocks and Zarr chunks must inflate, made
// without the library's code.
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
