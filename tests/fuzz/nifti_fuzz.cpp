// Fuzz target: the NIfTI-1 (.nii, or .nii.gz when the bytes are gzip) reader, through a temporary file
// (the volume readers take a path).
#include "fuzz/fuzz_checks.hpp"
#include "fuzz/fuzz_target.hpp"
#include "io/volume_formats.hpp"

KEYMESH_FUZZ_TARGET(nifti) {
  const bool gzip = data.size() >= 2 && data[0] == '\x1f' && data[1] == '\x8b';
  keymesh::fuzz::expect_valid(keymesh::io::read_nifti(keymesh::fuzz::temp_file(data, gzip ? ".nii.gz" : ".nii")));
}
