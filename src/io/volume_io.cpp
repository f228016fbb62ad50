#include "keymesh/io/volume_io.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "keymesh/io/plane_source.hpp"
#include "keymesh/io/volume_formats.hpp"

namespace keymesh::io {

namespace {

bool ends_with(const std::string& path, const std::string& suffix) {
  if (path.size() < suffix.size()) return false;
  std::string tail = path.substr(path.size() - suffix.size());
  std::transform(tail.begin(), tail.end(), tail.begin(), [](unsigned char c) { return std::tolower(c); });
  return tail == suffix;
}

}  // namespace

namespace {
ImageGrid read_volume_unchecked(const std::string& path, const RawOptions* raw) {
  if (raw) return read_raw(path, *raw);
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return read_all_planes(*open_volume_planes(path, nullptr));
  if (ends_with(path, ".raw"))
    throw InputError(path + ": a .raw volume needs --dims X Y Z and --type (and --spacing, --endian if not 1 / little)");
  if (ends_with(path, ".nrrd") || ends_with(path, ".nhdr")) return read_nrrd(path);
  if (ends_with(path, ".vti")) return read_vti(path);
  if (ends_with(path, ".nii") || ends_with(path, ".nii.gz")) return read_nifti(path);
  if (ends_with(path, ".den")) return read_den(path);
  throw InputError(path + ": unknown volume format (expected .vti, .nrrd, .nhdr, .nii, .nii.gz, .den, a DICOM or Zarr folder, or .raw with --dims)");
}
}  // namespace

ImageGrid read_volume(const std::string& path, const RawOptions* raw) {
  ImageGrid grid = read_volume_unchecked(path, raw);
  check_float32_geometry(grid.dims, grid.origin, grid.spacing, path);
  return grid;
}

void write_volume(const ImageGrid& grid, const std::string& path) {
  if (ends_with(path, ".vti")) return write_vti(grid, path);
  if (ends_with(path, ".nrrd")) return write_nrrd(grid, path);
  if (ends_with(path, ".raw")) return write_raw(grid, path);
  throw InputError(path + ": cannot write this volume format (expected .vti, .nrrd or .raw)");
}

}  // namespace keymesh::io
