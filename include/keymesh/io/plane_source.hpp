#pragma once
// Volumes read plane by plane for streamed contouring
// (keymesh/generate/contour_stream.hpp): so far raw files described by
// RawOptions, read with a seek per slab (either byte order).
#include <memory>
#include <string>

#include "keymesh/generate/contour_stream.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::io {

// Throws InputError naming the file when it is shorter than the header
// bytes plus the samples the dims declare.
std::unique_ptr<generate::PlaneSource> open_raw_planes(const std::string& path, const RawOptions& options);

}  // namespace keymesh::io
