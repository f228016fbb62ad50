// Fuzz target: the OBJ reader on bytes in memory (io::parse_obj).
#include "fuzz/fuzz_checks.hpp"
#include "fuzz/fuzz_target.hpp"
#include "io/mesh_formats.hpp"

KEYMESH_FUZZ_TARGET(obj) { keymesh::fuzz::expect_valid(keymesh::io::parse_obj(data, "fuzz.obj")); }
