// Fuzz target: the VolPack .den reader, through a temporary file
// (the volume readers take a path).
#include "fuzz/fuzz_checks.hpp"
#include "fuzz/fuzz_target.hpp"
#include "io/volume_formats.hpp"

KEYMESH_FUZZ_TARGET(den) {
  keymesh::fuzz::expect_valid(keymesh::io::read_den(keymesh::fuzz::temp_file(data, ".den")));
}
