#pragma once
// Zarr v2 arrays and OME-Zarr images (connectomics, microscopy: chunked
// arrays in a folder), read chunk by chunk.
//
// A folder holding `.zarray` is an array; a folder whose `.zattrs` holds
// OME-NGFF `multiscales` is an image, read at its first (full resolution)
// level; give a level's own folder (`image.zarr/2`) to read another one.
// Arrays: C order, 3 dimensions or more with every axis before the last
// three of size 1 (OME's t and c), dtypes u1 i1 u2 i2 i4 f4 f8 (either byte
// order), compressor none, zlib, gzip or blosc (any of its codecs), no
// filters, '.' or '/' dimension separator; absent chunks hold fill_value
// (absent from the listing of their directory: a chunk file that is there
// but cannot be read, a link loop, is refused naming the chunk).
// The last axis is x (fastest in memory), then y, then z: the bytes of a
// C-order (z, y, x) array are the grid's samples in order. Spacing and
// origin come from the OME scale and translation transforms of the level
// (and of the multiscale), of the last three axes; 1 and 0 otherwise.
// Anything else is refused by name (Fortran order, filters, other codecs,
// 64-bit integers, a non-spatial axis of size > 1).
#include <memory>
#include <string>

#include "keymesh/mesh/plane_source.hpp"

namespace keymesh::io {

// True when the folder holds .zarray, .zattrs or .zgroup, or is named *.zarr.
bool is_zarr_folder(const std::string& folder);

// Parses the metadata; planes are then read a chunk row at a time (every
// chunk overlapping the planes is decoded once per call), so
// --memory-limit streams an array whose chunks span few z-planes.
std::unique_ptr<PlaneSource> open_zarr(const std::string& folder);

}  // namespace keymesh::io
