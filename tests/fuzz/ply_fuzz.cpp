// Fuzz target: the PLY reader on bytes in memory (io::parse_ply).
#include "fuzz/fuzz_checks.hpp"
#include "fuzz/fuzz_target.hpp"
#include "io/mesh_formats.hpp"

KEYMESH_FUZZ_TARGET(ply) { keymesh::fuzz::expect_valid(keymesh::io::parse_ply(data, "fuzz.ply")); }
