#include "keymesh/io/plane_source.hpp"

#include <bit>
#include <string>
#include <utility>

#include "keymesh/core/error.hpp"
#include "keymesh/io/volume_formats.hpp"

namespace keymesh::io {

namespace {

class RawPlanes : public generate::PlaneSource {
 public:
  RawPlanes(std::string path, const RawOptions& o) : path_(std::move(path)), options_(o) {
    head_.dims = o.dims;
    head_.type = o.type;
    head_.spacing = o.spacing;
    head_.origin = o.origin;
    const std::uint64_t bytes = detail::checked_byte_count(o.dims, o.type, path_);
    const std::uint64_t have = detail::file_size_or_throw(path_);
    if (o.header_bytes < 0 || static_cast<std::uint64_t>(o.header_bytes) > have ||
        bytes > have - static_cast<std::uint64_t>(o.header_bytes))
      throw InputError(path_ + ": file holds " + std::to_string(have) + " bytes, " + std::to_string(o.dims[0]) + "x" +
                       std::to_string(o.dims[1]) + "x" + std::to_string(o.dims[2]) + " " + scalar_type_name(o.type) +
                       " samples after " + std::to_string(o.header_bytes) + " header bytes need " +
                       std::to_string(bytes + static_cast<std::uint64_t>(o.header_bytes)));
  }
  const ImageGrid& header() const override { return head_; }
  void read_planes(Id first, Id count, std::byte* out) override {
    const std::uint64_t size = scalar_size(head_.type);
    const std::uint64_t plane = static_cast<std::uint64_t>(head_.dims[0] * head_.dims[1]) * size;
    detail::read_exact(path_, static_cast<std::uint64_t>(options_.header_bytes) + plane * static_cast<std::uint64_t>(first),
                       out, plane * static_cast<std::uint64_t>(count), "planes " + std::to_string(first) + ".." +
                                                                         std::to_string(first + count - 1));
    if (options_.big_endian != (std::endian::native == std::endian::big) && size > 1) {
      const std::uint64_t n = plane * static_cast<std::uint64_t>(count);
      for (std::uint64_t i = 0; i < n; i += size)
        for (std::uint64_t a = 0, b = size - 1; a < b; ++a, --b) std::swap(out[i + a], out[i + b]);
    }
  }

 private:
  std::string path_;
  RawOptions options_;
  ImageGrid head_;
};

}  // namespace

std::unique_ptr<generate::PlaneSource> open_raw_planes(const std::string& path, const RawOptions& options) {
  return std::make_unique<RawPlanes>(path, options);
}

}  // namespace keymesh::io
