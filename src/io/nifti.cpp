// NIfTI-1 single files (.nii, .nii.gz): a 348-byte header, data at
// vox_offset. Voxel sizes from pixdim; scl_slope/scl_inter applied.
#include <unistd.h>
#include <zlib.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <optional>
#include <type_traits>

#include "keymesh/io/input_file.hpp"
#include "keymesh/mesh/label_scalars.hpp"
#include "volume_formats.hpp"
#include "whole_inflate.hpp"

namespace keymesh::io {

namespace {

// zlib over a file opened as every input is (regular files only).
gzFile open_gz(const std::string& path) {
  InputFile in(path);
  const int fd = ::dup(fileno(in.stream()));
  gzFile gz = fd >= 0 ? gzdopen(fd, "rb") : nullptr;
  if (!gz) {
    if (fd >= 0) ::close(fd);
    throw InputError(path + ": cannot open");
  }
  return gz;
}

// A gzip or plain stream read with zlib (gzread passes plain files through),
// never further than the caller asks.
class Stream {
 public:
  // `buffer`: zlib reads that many compressed bytes at a time and inflates
  // up to twice as many ahead of what is asked.
  Stream(const std::string& path, unsigned buffer) : path_(path), gz_(open_gz(path)) { gzbuffer(gz_, buffer); }
  ~Stream() { gzclose(gz_); }
  Stream(const Stream&) = delete;
  Stream& operator=(const Stream&) = delete;
  void read(void* dst, std::uint64_t size, const char* what) {
    auto* out = static_cast<unsigned char*>(dst);
    std::uint64_t done = 0;
    while (done < size) {
      const unsigned chunk = static_cast<unsigned>(std::min<std::uint64_t>(size - done, 1u << 30));
      const int got = gzread(gz_, out + done, chunk);
      if (got <= 0)
        throw InputError(path_ + ": truncated (" + what + ": " + std::to_string(done) + " of " + std::to_string(size) +
                         " bytes)");
      done += static_cast<std::uint64_t>(got);
    }
  }
  gzFile handle() { return gz_; }

 private:
  std::string path_;
  gzFile gz_;
};

// kDataBuffer for reading the samples with zlib; kHeaderBuffer for the
// header alone, where kDataBuffer inflates 2 MiB to give 348 bytes (18 M
// instructions). nifti_layout keeps kDataBuffer all the same: how far ahead
// it inflates decides whether a damage early in the stream is reported by
// it ("truncated (header...)") or by the reader after it, and its messages
// stay the ones it always gave.
constexpr unsigned kHeaderBuffer = 4 << 10, kDataBuffer = 1 << 20;

template <class T>
T get(const unsigned char* h, std::size_t offset, bool swap) {
  T v;
  std::memcpy(&v, h + offset, sizeof v);
  if (swap) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof v);
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    std::memcpy(&v, b, sizeof v);
  }
  return v;
}

// The layout the 348 header bytes of `path` (of file_bytes) declare, after
// every check of the header.
VolumeLayout header_layout(const unsigned char* h, const std::string& path, std::uint64_t file_bytes) {
  bool swap = false;
  if (get<std::int32_t>(h, 0, false) != 348) {
    if (get<std::int32_t>(h, 0, true) != 348) throw InputError(path + ": not a NIfTI-1 file (sizeof_hdr is not 348)");
    swap = true;
  }
  if (std::memcmp(h + 344, "n+1\0", 4) != 0) {
    if (std::memcmp(h + 344, "ni1\0", 4) == 0)
      throw InputError(path + ": two-file NIfTI (.hdr/.img) is not supported; convert to .nii");
    throw InputError(path + ": not a NIfTI-1 file (bad magic)");
  }
  std::int16_t dim[8];
  for (int i = 0; i < 8; ++i) dim[i] = get<std::int16_t>(h, 40 + 2 * i, swap);
  if (dim[0] < 3 || dim[0] > 7) throw InputError(path + ": NIfTI dim[0] = " + std::to_string(dim[0]) + " (need 3)");
  for (int i = 4; i <= dim[0]; ++i)
    if (dim[i] != 1) throw InputError(path + ": NIfTI volume has " + std::to_string(dim[0]) + " dimensions with dim[" +
                                      std::to_string(i) + "] = " + std::to_string(dim[i]) + " (only 3D scalar volumes)");
  const std::int16_t datatype = get<std::int16_t>(h, 70, swap);
  ScalarType type;
  switch (datatype) {
    case 2: type = ScalarType::UInt8; break;
    case 4: type = ScalarType::Int16; break;
    case 8: type = ScalarType::Int32; break;
    case 16: type = ScalarType::Float32; break;
    case 64: type = ScalarType::Float64; break;
    case 256: type = ScalarType::Int8; break;
    case 512: type = ScalarType::UInt16; break;
    case 768: type = ScalarType::UInt32; break;
    case 1024: type = ScalarType::Int64; break;
    case 1280: type = ScalarType::UInt64; break;
    default:
      throw InputError(path + ": NIfTI datatype " + std::to_string(datatype) +
                       " is not supported (uint8, int8, int16, uint16, int32, uint32, int64, uint64, float32, float64)");
  }
  const float vox_offset = get<float>(h, 108, swap);
  if (!(vox_offset >= 348) || vox_offset > 1.0e9f || vox_offset != std::floor(vox_offset))
    throw InputError(path + ": NIfTI vox_offset " + std::to_string(vox_offset) + " is invalid");
  std::array<double, 3> spacing{};
  for (int a = 0; a < 3; ++a) {
    const double p = std::abs(static_cast<double>(get<float>(h, 76 + 4 * (a + 1), swap)));
    spacing[a] = (p > 0 && std::isfinite(p)) ? p : 1.0;
  }
  const std::array<Id, 3> dims{dim[1], dim[2], dim[3]};
  for (int a = 0; a < 3; ++a)
    if (dims[a] <= 0) throw InputError(path + ": NIfTI dim[" + std::to_string(a + 1) + "] = " + std::to_string(dims[a]));
  const std::uint64_t need = detail::checked_byte_count(dims, type, path);
  const bool gz = path.size() > 3 && path.compare(path.size() - 3, 3, ".gz") == 0;
  const auto offset = static_cast<std::uint64_t>(vox_offset);
  const std::string declared = std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]) +
                               " " + scalar_type_name(type) + " volume at vox_offset " + std::to_string(offset);
  // A plain file must hold the data; gzip cannot expand by more than ~1032:1.
  if (!gz && (offset > file_bytes || need > file_bytes - offset))
    throw InputError(path + ": file holds " + std::to_string(file_bytes) + " bytes, the header declares a " + declared);
  if (gz && need / 1032 > file_bytes + 64)
    throw InputError(path + ": gzip file of " + std::to_string(file_bytes) + " bytes cannot hold the declared " +
                     declared);
  VolumeLayout layout;
  layout.data_path = path;
  layout.raw.dims = dims;
  layout.raw.type = type;
  layout.raw.spacing = spacing;
  layout.raw.big_endian = swap == (std::endian::native == std::endian::little);
  layout.raw.header_bytes = static_cast<Id>(offset);
  if (gz) layout.compressed = "gzip";
  const float slope = get<float>(h, 112, swap), inter = get<float>(h, 116, swap);
  if (std::isfinite(slope) && std::isfinite(inter) && slope != 0 && !(slope == 1 && inter == 0)) {
    layout.scale_slope = slope;
    layout.scale_inter = inter;
  }
  return layout;
}

// Swaps to native order, then applies the scaling the layout declares.
ImageGrid finish_samples(ImageGrid grid, const VolumeLayout& layout) {
  if (layout.raw.big_endian != (std::endian::native == std::endian::big)) detail::swap_samples(grid);
  if (!layout.scaled()) return grid;
  // Scaled data: the real values are slope * stored + inter.
  ImageGrid scaled;
  scaled.allocate_unwritten(grid.dims, detail::scaled_type(grid.type));
  scaled.spacing = grid.spacing;
  scaled.name = grid.name;
  detail::scale_samples(grid.type, grid.bytes.data(), scaled.bytes.data(), static_cast<std::uint64_t>(grid.num_points()),
                        layout.scale_slope, layout.scale_inter);
  return scaled;
}

// A .nii.gz whose gzip members are clean (whole_inflate.hpp), its header
// read through a small zlib buffer and its samples inflated by libdeflate.
// std::nullopt for anything else, the header's refusals included: the zlib
// read then gives its own result or message, and as it inflates further
// ahead for the header (kDataBuffer) it may meet a damage in the stream
// before a check of the header would.
std::optional<ImageGrid> read_clean_gzip(const std::string& path) {
  VolumeLayout layout;
  try {
    const std::uint64_t file_bytes = detail::file_size_or_throw(path);
    unsigned char h[348];
    Stream in(path, kHeaderBuffer);
    in.read(h, sizeof h, "header");
    layout = header_layout(h, path, file_bytes);
  } catch (const InputError&) {
    return std::nullopt;
  } catch (const LimitError&) {
    return std::nullopt;
  }
  const std::uint64_t need = detail::checked_byte_count(layout.raw.dims, layout.raw.type, path);
  auto samples = detail::inflate_gzip_file(path, 0, static_cast<std::uint64_t>(layout.raw.header_bytes), need);
  if (!samples) return std::nullopt;
  ImageGrid grid;
  grid.spacing = layout.raw.spacing;
  grid.name = layout.name;
  detail::adopt_samples(grid, layout.raw.dims, layout.raw.type, std::move(*samples));
  return finish_samples(std::move(grid), layout);
}

}  // namespace

VolumeLayout nifti_layout(const std::string& path) {
  const std::uint64_t file_bytes = detail::file_size_or_throw(path);
  unsigned char h[348];
  {
    Stream in(path, kDataBuffer);
    in.read(h, sizeof h, "header");
  }
  return header_layout(h, path, file_bytes);
}

ImageGrid read_nifti(const std::string& path) {
  const bool gz = path.size() > 3 && path.compare(path.size() - 3, 3, ".gz") == 0;
  if (gz)
    if (auto grid = read_clean_gzip(path)) return std::move(*grid);
  // zlib: plain data, or gzip that is not clean.
  const VolumeLayout layout = nifti_layout(path);
  const std::uint64_t file_bytes = detail::file_size_or_throw(path);
  const std::array<Id, 3> dims = layout.raw.dims;
  const ScalarType type = layout.raw.type;
  const std::uint64_t need = detail::checked_byte_count(dims, type, path);
  const auto offset = static_cast<std::uint64_t>(layout.raw.header_bytes);
  Stream in(path, kDataBuffer);
  unsigned char h[348];
  in.read(h, sizeof h, "header");
  ImageGrid grid;
  grid.spacing = layout.raw.spacing;
  grid.name = layout.name;
  // Skip to vox_offset, then read exactly the declared samples.
  std::uint64_t skip = offset - 348;
  unsigned char pad[4096];
  while (skip > 0) {
    const std::uint64_t n = std::min<std::uint64_t>(skip, sizeof pad);
    in.read(pad, n, "extension");
    skip -= n;
  }
  if (!layout.compressed.empty()) {
    detail::adopt_samples(grid, dims, type, detail::read_gz_growing(in.handle(), need, file_bytes, path, "voxel data", true));
  } else {
    detail::allocate_checked(grid, dims, type, path);
    in.read(grid.data(), grid.bytes.size(), "voxel data");
  }
  return finish_samples(std::move(grid), layout);
}

namespace detail {

ScalarType scaled_type(ScalarType stored_type) {
  return stored_type == ScalarType::Float64 ? ScalarType::Float64 : ScalarType::Float32;
}

void scale_samples(ScalarType stored_type, const std::byte* stored, std::byte* out, std::uint64_t n, double slope,
                   double inter) {
  // Typed views of both buffers, dispatched by visit_scalars.
  ImageGrid in, to;
  in.dims = to.dims = {static_cast<Id>(n), 1, 1};
  in.type = stored_type;
  in.external = stored;
  to.type = scaled_type(stored_type);
  to.external = out;
  visit_any_scalars(in, [&](const auto* s) {
    visit_scalars(to, [&](const auto* d_const) {
      using D = std::remove_cv_t<std::remove_pointer_t<decltype(d_const)>>;
      D* d = const_cast<D*>(d_const);
      for (std::uint64_t i = 0; i < n; ++i) d[i] = static_cast<D>(slope * static_cast<double>(s[i]) + inter);
      return 0;
    });
    return 0;
  });
}

}  // namespace detail

}  // namespace keymesh::io
