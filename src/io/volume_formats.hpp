#pragma once
// The volume formats, one implementation file each (src/io/raw.cpp,
// nrrd.cpp, vti.cpp, nifti.cpp, den.cpp); volume_io.hpp dispatches to them.
// Every reader checks declared sizes against the bytes present before it
// allocates, never inflates compressed data past the declared size, and
// throws InputError (or LimitError for sizes past what is supported) with
// the path and the problem.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "keymesh/io/volume_io.hpp"
#include "keymesh/mesh/plane_source.hpp"

namespace keymesh::io {

// Where the samples of a volume file lie, parsed from its header with the
// same checks as the reader (dims, sizes against the bytes present): what
// reading the volume plane by plane needs (io/plane_source.hpp).
struct VolumeLayout {
  std::string data_path;   // the file holding the samples (a .nhdr's data file)
  RawOptions raw;          // dims, type, spacing, origin, byte order; header_bytes = data offset
  std::string compressed;  // "gzip" when the samples cannot be read by offset
  double scale_slope = 1, scale_inter = 0;  // NIfTI: value = slope * stored + inter
  std::string name = volume_field_name();   // the scalar field's name (.vti: its array's)
  bool scaled() const { return !(scale_slope == 1 && scale_inter == 0); }
};
VolumeLayout nrrd_layout(const std::string& path);
VolumeLayout nifti_layout(const std::string& path);
// A .vti whose point array is appended raw and uncompressed (as keymesh
// writes it; ParaView with compression off); otherwise `compressed` says why it cannot be
// read by offset.
VolumeLayout vti_layout(const std::string& path);
// Planes of the volume a layout describes (io/plane_source.cpp): what the
// format table's open_planes are for NRRD, NIfTI and .vti. InputError
// naming the file when its samples cannot be read by offset or inflated in
// order (a zlib .vti, base64 or ascii samples).
std::unique_ptr<PlaneSource> open_nrrd_planes(const std::string& path);
std::unique_ptr<PlaneSource> open_nifti_planes(const std::string& path);
std::unique_ptr<PlaneSource> open_vti_planes(const std::string& path);

ImageGrid read_raw(const std::string& path, const RawOptions& options);
void write_raw(const ImageGrid& grid, const std::string& path);  // native little-endian samples only

// NRRD: .nrrd (attached) or .nhdr (detached, "data file:" relative to the header).
ImageGrid read_nrrd(const std::string& path);
void write_nrrd(const ImageGrid& grid, const std::string& path);  // attached, raw, little endian

// VTK XML ImageData (.vti), one single-component point array.
ImageGrid read_vti(const std::string& path);
void write_vti(const ImageGrid& grid, const std::string& path);   // appended raw, UInt64 header

// NIfTI-1 single file (.nii, .nii.gz).
ImageGrid read_nifti(const std::string& path);

// VolPack density file (.den): uint8.
ImageGrid read_den(const std::string& path);

namespace detail {
// Size of a file in bytes; InputError naming the path when it cannot be read.
std::uint64_t file_size_or_throw(const std::string& path);
// Reads `size` bytes at `offset` of the file into dst; InputError when the
// file is shorter.
void read_exact(const std::string& path, std::uint64_t offset, void* dst, std::uint64_t size, const std::string& what);
// Swaps the byte order of every sample in place.
void swap_samples(ImageGrid& grid);
// Checks dims, then allocates; `what` names the source in messages.
void allocate_checked(ImageGrid& grid, std::array<Id, 3> dims, ScalarType type, const std::string& path);
// Bytes of samples dims x type need, after the checks allocate_checked makes
// (each dim positive, no overflow): InputError / LimitError naming path.
std::uint64_t checked_byte_count(std::array<Id, 3> dims, ScalarType type, const std::string& path);
// The first allocation for `size` bytes inflated from `compressed_bytes`:
// at most size, and no more than the data is likely to inflate to, so that
// a header declaring more than the stream holds costs little.
std::uint64_t initial_inflate_bytes(std::uint64_t compressed_bytes, std::uint64_t size);
// Reads exactly `size` bytes of an opened zlib/gzip stream (gzFile, passed
// as void* to keep <zlib.h> out of this header) into a buffer that grows as
// the data arrives: a header declaring more than the stream holds costs no
// more memory than the stream really inflates to, and nothing past `size`
// is ever inflated. `compressed_bytes` (the stream's size on disk) sizes the
// first allocation (initial_inflate_bytes). InputError naming path and `what` when the stream ends
// early or is corrupt, or (unless allow_plain) is not gzip data at all.
Array<std::byte> read_gz_growing(void* gz_file, std::uint64_t size, std::uint64_t compressed_bytes,
                                       const std::string& path, const std::string& what, bool allow_plain);
// NIfTI scaling: value = slope * stored + inter, computed in double and
// stored as float32 (float64 input stays float64: scaled_type). `out` holds
// n samples of scaled_type(stored_type).
ScalarType scaled_type(ScalarType stored_type);
void scale_samples(ScalarType stored_type, const std::byte* stored, std::byte* out, std::uint64_t n, double slope,
                   double inter);
// Moves samples read by read_gz_growing into grid (dims already checked).
void adopt_samples(ImageGrid& grid, std::array<Id, 3> dims, ScalarType type, Array<std::byte> samples);
}  // namespace detail

}  // namespace keymesh::io
