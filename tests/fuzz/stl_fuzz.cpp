// Fuzz target: the STL reader on bytes in memory (io::parse_stl).
#include "fuzz/fuzz_checks.hpp"
#include "fuzz/fuzz_target.hpp"
#include "io/mesh_formats.hpp"

KEYMESH_FUZZ_TARGET(stl) { keymesh::fuzz::expect_valid(keymesh::io::parse_stl(data, "fuzz.stl")); }
