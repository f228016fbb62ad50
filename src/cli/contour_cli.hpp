#pragma once
// `keymesh contour`: its options as given, and the pieces its paths share.
// The paths (src/cli/contour_cmd.cpp, contour_distributed.cpp):
//   run_voxels    a volume read whole, marching cubes;
//   run_tets      a tetrahedral grid (.vtu .vtk), marching tetrahedra;
//   run_streamed  --memory-limit: the volume in slabs of z-planes;
//   run_distributed_contour  under mpirun: each rank reads and contours its slab;
//   run_coarse_pieces  (contour_coarse_pieces.cpp) its --coarsen: coarse pieces, written or gathered.
#include <string>
#include <vector>

#include "command.hpp"
#include "raw_input.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/mesh/plane_source.hpp"

namespace keymesh::cli {

struct ContourCli {
  std::string input, output;
  std::vector<double> isovalues;
  std::string weld = "keyreduce";
  std::string normals = "none";
  bool no_scalars = false;
  bool coarsen = false;
  bool curvature = false;
  bool history = false;      // history_key and history_t per point (.vtp)
  std::string array;         // tet grids: the point field to contour
  std::string memory_limit;  // stream the volume in slabs
  bool gather = false;       // under mpirun: one file from rank 0
  bool balance = false;      // under mpirun: slabs by work
  RawInputCli raw_input;     // a headerless .raw volume
  CommonOptions common;
};

// The library's options for the options given (names parsed by
// generate/option_names.hpp; checked already by the CLI).
generate::ContourOptions contour_options(const ContourCli& o);

// The report keys every path has: the files, isovalues, weld and normals
// as given, the counts, threads and per-stage seconds.
nlohmann::json contour_report(const ContourCli& o, long long points, long long cells, int threads,
                              const StageTimer& timer);

// --coarsen: what the collapse did to the topology (triangles_before,
// triangles_after, nonmanifold_edges, nonmanifold_vertices, boundary_edges),
// timed as "check"; non-manifold parts are said on stderr unless quiet.
nlohmann::json coarsening_report(const ContourCli& o, const SurfaceMesh& mesh, Id triangles_before,
                                 StageTimer& timer);

// --history's usage errors (exit 2, said on stderr when `say`): no
// coarsening, a .vtp output (history_key is UInt64, which the other formats
// cannot hold; under mpirun also .pvtp pieces). 0 when none.
int refuse_history_usage(const ContourCli& o, bool say, bool distributed);

// The mesh written to o.output: with --history (.vtp, checked) its
// history_key array beside the mesh's history_t field.
void write_contour(const ContourCli& o, const SurfaceMesh& mesh, const std::vector<std::uint64_t>& history_key);

// Output OUT.pvtp: one OUT_<rank>.vtp piece per rank (points with their
// global ids) and the index; any other extension (or --gather): the whole
// mesh gathered on rank 0, byte-identical to the single-process file.
// Returns the exit code (every rank returns the same).
int run_distributed_contour(const ContourCli& o, const generate::ContourOptions& options, int threads);

// --coarsen under mpirun: every rank its piece of the coarse surface, made
// from its layers and a halo (distributed/coarse_pieces.hpp); welded by their
// global ids, the one process's output. Into OUT.pvtp every rank writes its
// piece, nothing gathered; into any other file the coarse pieces (never the
// fine mesh) are gathered on rank 0, which writes the one process's file
// byte for byte. memory_limit (--memory-limit, 0: none) streams the rank's
// planes in slabs.
int run_coarse_pieces(const ContourCli& o, const generate::ContourOptions& options, PlaneSource& source,
                      int threads, std::size_t memory_limit);

}  // namespace keymesh::cli
