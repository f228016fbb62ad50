#include "keymesh/io/plane_source.hpp"

#include <bit>
#include <vector>
#include <string>
#include <utility>

#include "keymesh/core/error.hpp"
#include "keymesh/io/formats.hpp"
#include "gzip_plane_reader.hpp"
#include "volume_formats.hpp"

namespace keymesh::io {

namespace {

class RawPlanes : public PlaneSource {
 public:
  RawPlanes(std::string path, const RawOptions& o, std::string name, double slope = 1, double inter = 0)
      : path_(std::move(path)), options_(o), slope_(slope), inter_(inter) {
    set_header(o, std::move(name));
    const std::uint64_t bytes = detail::checked_byte_count(o.dims, o.type, path_);
    check_float32_geometry(o.dims, o.origin, o.spacing, path_);
    const std::uint64_t have = detail::file_size_or_throw(path_);
    if (o.header_bytes < 0 || static_cast<std::uint64_t>(o.header_bytes) > have ||
        bytes > have - static_cast<std::uint64_t>(o.header_bytes))
      throw InputError(path_ + ": file holds " + std::to_string(have) + " bytes, " + std::to_string(o.dims[0]) + "x" +
                       std::to_string(o.dims[1]) + "x" + std::to_string(o.dims[2]) + " " + scalar_type_name(o.type) +
                       " samples after " + std::to_string(o.header_bytes) + " header bytes need " +
                       std::to_string(bytes + static_cast<std::uint64_t>(o.header_bytes)));
  }
  // gzip-compressed samples, inflated once in order (see GzipPlaneReader):
  // the stream starts at file_offset and its first `skip` bytes are header.
  RawPlanes(std::string path, const RawOptions& o, std::string name, std::uint64_t file_offset, std::uint64_t skip,
            double slope, double inter)
      : path_(std::move(path)), options_(o), slope_(slope), inter_(inter) {
    set_header(o, std::move(name));
    detail::checked_byte_count(o.dims, o.type, path_);
    gzip_ = std::make_unique<GzipPlaneReader>(path_, file_offset, skip,
                                              static_cast<std::uint64_t>(o.dims[0] * o.dims[1]) * scalar_size(o.type));
  }
  const ImageGrid& header() const override { return head_; }
  void read_planes(Id first, Id count, std::byte* out) override {
    if (scaled()) {
      // Stored samples into a buffer, then value = slope * stored + inter.
      const std::uint64_t n = static_cast<std::uint64_t>(head_.dims[0] * head_.dims[1]) * static_cast<std::uint64_t>(count);
      std::vector<std::byte> stored(n * scalar_size(options_.type));
      read_stored(first, count, stored.data());
      detail::scale_samples(options_.type, stored.data(), out, n, slope_, inter_);
      return;
    }
    read_stored(first, count, out);
  }

 private:
  void set_header(const RawOptions& o, std::string name) {
    head_.name = std::move(name);
    head_.dims = o.dims;
    head_.type = o.type;
    head_.spacing = o.spacing;
    head_.origin = o.origin;
    // Scaled samples (NIfTI scl_slope/scl_inter) come out as float, as read_nifti gives them.
    if (scaled()) head_.type = detail::scaled_type(o.type);
  }

  bool scaled() const { return !(slope_ == 1 && inter_ == 0); }

  void read_stored(Id first, Id count, std::byte* out) {
    const std::uint64_t size = scalar_size(options_.type);
    const std::uint64_t plane = static_cast<std::uint64_t>(head_.dims[0] * head_.dims[1]) * size;
    if (gzip_) gzip_->read(first, count, out);
    else
      detail::read_exact(path_, static_cast<std::uint64_t>(options_.header_bytes) + plane * static_cast<std::uint64_t>(first),
                       out, plane * static_cast<std::uint64_t>(count), "planes " + std::to_string(first) + ".." +
                                                                         std::to_string(first + count - 1));
    if (options_.big_endian != (std::endian::native == std::endian::big) && size > 1) {
      const std::uint64_t n = plane * static_cast<std::uint64_t>(count);
      for (std::uint64_t i = 0; i < n; i += size)
        for (std::uint64_t a = 0, b = size - 1; a < b; ++a, --b) std::swap(out[i + a], out[i + b]);
    }
  }

  std::string path_;
  RawOptions options_;
  double slope_, inter_;
  ImageGrid head_;
  std::unique_ptr<GzipPlaneReader> gzip_;
};

}  // namespace

std::unique_ptr<PlaneSource> open_raw_planes(const std::string& path, const RawOptions& options) {
  return std::make_unique<RawPlanes>(path, options, volume_field_name());
}

namespace {
// The samples a header describes, read by offset, or inflated in order when
// they are gzip-compressed. `whole_stream`: the gzip stream holds the header
// too (a .nii.gz) rather than starting at the data offset (a gzip NRRD).
std::unique_ptr<PlaneSource> open_layout_planes(const std::string& path, const VolumeLayout& layout,
                                                bool whole_stream) {
  if (layout.compressed == "gzip") {
    const auto at = static_cast<std::uint64_t>(layout.raw.header_bytes);
    return std::make_unique<RawPlanes>(layout.data_path, layout.raw, layout.name, whole_stream ? 0 : at,
                                       whole_stream ? at : 0, layout.scale_slope, layout.scale_inter);
  }
  if (!layout.compressed.empty())
    throw InputError(path + ": " + layout.compressed + " samples cannot be read plane by plane "
                     "(convert it, e.g. `keymesh convert " + path + " out.nrrd`)");
  return std::make_unique<RawPlanes>(layout.data_path, layout.raw, layout.name, layout.scale_slope,
                                     layout.scale_inter);
}
}  // namespace

std::unique_ptr<PlaneSource> open_nrrd_planes(const std::string& path) {
  return open_layout_planes(path, nrrd_layout(path), false);
}
std::unique_ptr<PlaneSource> open_nifti_planes(const std::string& path) {
  return open_layout_planes(path, nifti_layout(path), true);
}
std::unique_ptr<PlaneSource> open_vti_planes(const std::string& path) {
  return open_layout_planes(path, vti_layout(path), false);
}

std::unique_ptr<PlaneSource> open_volume_planes(const std::string& path, const RawOptions* raw) {
  if (raw) return open_raw_planes(path, *raw);
  const Format* format = input_format(path);
  if (!format || format->kind != DataKind::Volume || !format->open_planes)
    throw InputError(path + ": cannot be read plane by plane (" + accepted_plane_sources() +
                     " can; convert with `keymesh convert " + path + " out.nrrd`)");
  return format->open_planes(path);
}

}  // namespace keymesh::io

namespace keymesh::io {

ImageGrid read_all_planes(PlaneSource& source) {
  const ImageGrid& head = source.header();
  ImageGrid grid;
  grid.spacing = head.spacing;
  grid.origin = head.origin;
  grid.name = head.name;
  grid.allocate_unwritten(head.dims, head.type);
  source.read_planes(0, head.dims[2], grid.bytes.data());
  return grid;
}

}  // namespace keymesh::io
