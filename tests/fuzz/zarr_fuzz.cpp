// Fuzz target: the Zarr v2 / OME-Zarr reader on a folder packed into the
// input (fuzz/folder_input.hpp: .zarray, .zattrs and chunk files; "@open"
// to read a level by its own folder); the planes read within fuzz_checks'
// budget.
#include "fuzz/folder_input.hpp"
#include "fuzz/fuzz_checks.hpp"
#include "fuzz/fuzz_target.hpp"
#include "io/zarr.hpp"

KEYMESH_FUZZ_TARGET(zarr) {
  const auto array = keymesh::io::open_zarr(keymesh::fuzz::temp_folder(data, "in.zarr"));
  keymesh::fuzz::expect_valid_planes(*array);
}
