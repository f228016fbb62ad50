// Fuzz target: the DICOM series reader (GDCM's scanner for the headers, its
// ImageReader for the pixels) on a folder of slices packed into the input
// (fuzz/folder_input.hpp); the planes read within fuzz_checks' budget.
#include "fuzz/folder_input.hpp"
#include "fuzz/fuzz_checks.hpp"
#include "fuzz/fuzz_target.hpp"
#include "io/dicom.hpp"

KEYMESH_FUZZ_TARGET(dicom) {
  const auto series = keymesh::io::open_dicom_series(keymesh::fuzz::temp_folder(data, "series"));
  keymesh::fuzz::expect_valid_planes(*series);
}
