// Fuzz target: the VTK XML ImageData reader, through a temporary file
// (the volume readers take a path).
#include "fuzz/fuzz_checks.hpp"
#include "fuzz/fuzz_target.hpp"
#include "fuzz/xml_mutator.hpp"
#include "io/volume_formats.hpp"

KEYMESH_FUZZ_TARGET(vti) {
  keymesh::fuzz::expect_valid(keymesh::io::read_vti(keymesh::fuzz::temp_file(data, ".vti")));
}
