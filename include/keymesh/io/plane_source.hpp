#pragma once
// Volumes read plane by plane for streamed and distributed contouring
// (keymesh/generate/contour/contour_stream.hpp, keymesh/distributed): raw files
// described by RawOptions and uncompressed NRRD / NIfTI, read with a seek
// per slab (either byte order).
#include <memory>
#include <string>

#include "keymesh/mesh/plane_source.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::io {

// Throws InputError naming the file when it is shorter than the header
// bytes plus the samples the dims declare.
std::unique_ptr<PlaneSource> open_raw_planes(const std::string& path, const RawOptions& options);

// Raw (when `raw` is given), or a .nrrd/.nhdr, .nii(.gz) or .vti: the header
// parsed with the reader's checks, then planes read at their offset, or
// inflated in order when the samples are gzip-compressed (GzipPlaneReader:
// planes before the first asked for are inflated and dropped) (NIfTI
// scl_slope/scl_inter applied as read_volume applies them). Any other
// compression or format: InputError naming the file and what to do.
// A folder is a Zarr array or OME-Zarr image (io/zarr.hpp) when it holds
// Zarr metadata, else a DICOM series (io/dicom.hpp).
std::unique_ptr<PlaneSource> open_volume_planes(const std::string& path, const RawOptions* raw);

// Every plane of the source into one grid: how read_volume reads the formats
// whose reader is a plane source (DICOM series, Zarr).
ImageGrid read_all_planes(PlaneSource& source);

}  // namespace keymesh::io
