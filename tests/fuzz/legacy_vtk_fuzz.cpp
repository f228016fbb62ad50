// Fuzz target: the legacy VTK reader on bytes in memory (io::parse_legacy_vtk).
#include "fuzz/fuzz_checks.hpp"
#include "fuzz/fuzz_target.hpp"
#include "io/mesh_formats.hpp"

KEYMESH_FUZZ_TARGET(legacy_vtk) { keymesh::fuzz::expect_valid(keymesh::io::parse_legacy_vtk(data, "fuzz.vtk")); }
