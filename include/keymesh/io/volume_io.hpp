#pragma once
// Reading and writing voxel volumes. One file per format under io/; this
// header dispatches on the file name's extension.
//
// Read:  .raw (with RawOptions), .nrrd and detached .nhdr (raw and gzip
//        encodings), .vti (VTK XML ImageData: ascii, base64 inline, raw
//        appended; zlib-compressed or not), .nii / .nii.gz (NIfTI-1, with
//        scl_slope/scl_inter and pixdim), .den (VolPack).
// Write: .vti, .nrrd, .raw
#include <array>
#include <string>

#include "keymesh/mesh/image_grid.hpp"

namespace keymesh::io {

struct RawOptions {
  std::array<Id, 3> dims{0, 0, 0};
  ScalarType type = ScalarType::Float32;
  std::array<double, 3> spacing{1.0, 1.0, 1.0};
  std::array<double, 3> origin{0.0, 0.0, 0.0};
  bool big_endian = false;
  Id header_bytes = 0;  // bytes to skip at the start of the file
};

// The name of the scalar point field a volume file gives: one rule for every
// path that reads it (read_volume, the plane sources of --memory-limit and
// mpirun, Python's keymesh.read), so that their outputs are byte-identical.
// The name the file stores for its array (`stored`), else "scalars"
// (ImageGrid's default name). Of the formats read, only .vti stores one (its point
// DataArray's Name; an empty Name counts as none); raw, NRRD, NIfTI, VolPack
// .den, DICOM and Zarr store none (docs/decisions/
// scalar-field-name.md).
std::string volume_field_name(const std::string* stored = nullptr);

// Throws InputError with the path and the problem on any malformed input.
// `raw` is required for .raw files and ignored otherwise.
ImageGrid read_volume(const std::string& path, const RawOptions* raw = nullptr);

// Writes atomically (temporary name, then rename).
void write_volume(const ImageGrid& grid, const std::string& path);

}  // namespace keymesh::io
