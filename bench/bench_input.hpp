#pragma once
// The input volume of the bench programs: the Spherical Distance field of
// `size`^3, or a volume file (keymesh::io::read_volume) when `file` is set,
// in which case `size` becomes its largest dimension. Exits with status 1
// and the reader's message when the file cannot be read.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::bench {

inline ImageGrid input_volume(const std::string& file, long long& size) {
  try {
    if (file.empty()) return generate::spherical_distance(size);
    ImageGrid grid = io::read_volume(file);
    size = static_cast<long long>(std::max({grid.dims[0], grid.dims[1], grid.dims[2]}));
    return grid;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    std::exit(1);
  }
}

}  // namespace keymesh::bench
