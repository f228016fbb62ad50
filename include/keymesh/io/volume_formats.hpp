#pragma once
// The volume formats, one implementation file each (src/io/raw.cpp,
// nrrd.cpp, vti.cpp, nifti.cpp, den.cpp); volume_io.hpp dispatches to them.
// Every reader checks declared sizes against the bytes present before it
// allocates, never inflates compressed data past the declared size, and
// throws InputError (or LimitError for sizes past what is supported) with
// the path and the problem.
#include <string>

#include "keymesh/io/volume_io.hpp"

namespace keymesh::io {

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
}  // namespace detail

}  // namespace keymesh::io
