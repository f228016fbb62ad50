// Fuzz target: the VTK XML UnstructuredGrid reader on bytes in memory (io::parse_vtu).
#include "fuzz/fuzz_checks.hpp"
#include "fuzz/fuzz_target.hpp"
#include "fuzz/xml_mutator.hpp"
#include "io/mesh_formats.hpp"

KEYMESH_FUZZ_TARGET(vtu) { keymesh::fuzz::expect_valid(keymesh::io::parse_vtu(data, "fuzz.vtu")); }
