#pragma once
// `mpirun -np P keymesh contour VOLUME -o OUT`: the distributed
// contour's command-line side (reading slabs, pieces or gather, report).
#include <string>

#include "keymesh/generate/contour.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::cli {

struct DistributedContourJob {
  std::string input, output, report_path;
  io::RawOptions raw;
  bool raw_given = false;  // raw input described by --dims ...; otherwise .nrrd/.nhdr/.nii
  generate::ContourOptions options;
  bool gather = false;  // --gather: one file written by rank 0
  bool balance = false; // --balance: slab boundaries by work, not by layer count
  bool quiet = false;
  int threads = 1;
  std::string weld, normals;  // as given, for the report
};

// Output OUT.pvtp: one OUT_<rank>.vtp piece per rank (points with their
// global ids) and the index; any other extension (or --gather): the whole
// mesh gathered on rank 0, byte-identical to the single-process file.
// Returns the exit code (every rank returns the same).
int run_distributed_contour(const DistributedContourJob& job);

}  // namespace keymesh::cli
