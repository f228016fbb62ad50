// Fuzz target: the VTP reader on bytes in memory (io::parse_vtp).
#include "fuzz/fuzz_checks.hpp"
#include "fuzz/fuzz_target.hpp"
#include "fuzz/xml_mutator.hpp"
#include "io/mesh_formats.hpp"

KEYMESH_FUZZ_TARGET(vtp) { keymesh::fuzz::expect_valid(keymesh::io::parse_vtp(data, "fuzz.vtp")); }
