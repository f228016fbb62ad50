#include "keymesh/io/volume_io.hpp"

#include "keymesh/core/error.hpp"
#include "keymesh/io/formats.hpp"
#include "volume_formats.hpp"

namespace keymesh::io {

namespace {
// A mesh or grid format given where a volume is read: said by kind,
// rather than "unknown volume format".
[[noreturn]] void refuse_non_volume(const std::string& path, const Format& f) {
  throw InputError(path + ": " + std::string(f.name) +
                   (f.kind == DataKind::Surface ? " is a surface mesh format" : " is an unstructured grid format") +
                   ", not a volume (expected " + accepted_volumes(false) + ")");
}

ImageGrid read_volume_unchecked(const std::string& path, const RawOptions* raw) {
  // Options describe raw samples whatever the file is called.
  if (raw) return read_raw(path, *raw);
  const Format* f = input_format(path);
  if (f && f->kind == DataKind::Volume && f->headerless)
    throw InputError(path + ": a " + std::string(f->extensions[0]) +
                     " volume needs --dims X Y Z and --type (and --spacing, --endian if not 1 / little)");
  if (const VolumeReader read = f ? function_of<VolumeReader>(*f) : nullptr) return read(path);
  if (f && f->kind != DataKind::Volume) refuse_non_volume(path, *f);
  refuse_format(path, DataKind::Volume, false);
}
}  // namespace

std::string volume_field_name(const std::string* stored) {
  // "scalars": ImageGrid's default name, which a grid made in memory keeps.
  return stored && !stored->empty() ? *stored : std::string(ImageGrid{}.name);
}

ImageGrid read_volume(const std::string& path, const RawOptions* raw) {
  ImageGrid grid = read_volume_unchecked(path, raw);
  check_float32_geometry(grid.dims, grid.origin, grid.spacing, path);
  return grid;
}

void write_volume(const ImageGrid& grid, const std::string& path) { function_for<VolumeWriter>(path)(grid, path); }

}  // namespace keymesh::io
