// Times marching cubes + weld on the Spherical Distance field in-process (no
// file I/O), for the paper's Table 2 rows. Prints one JSON line per case:
//   contour_bench --size 512 --threads 2 --reps 5
//                 [--weld keyreduce|keyreduce-sort|vertexweld]
//                 [--normals none|gradient|average] [--iso V] [--grid voxel|tet5]
//                 [--file VOLUME] [--iso V1,V2,...] [--coarsen on] [--scalars on]
// --file contours a volume file (any format keymesh::io::read_volume reads:
// .vti .nrrd .nii(.gz) .den) instead of generating the sphere; --iso is then
// required and "size" reports the largest dimension.
// --scalars on carries the interpolated scalar (as the Python module and the
// CLI do by default); off by default, as the peers are run.
// --grid tet5 contours the scheme-5 tetrahedralization of the field by
// marching tetrahedra; the tetrahedralization is timed once ("build").
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "keymesh/core/huge_pages.hpp"
#include "keymesh/generate/contour.hpp"
#include "keymesh/generate/contour_tets.hpp"
#include "keymesh/generate/tetrahedralize.hpp"
#include "keymesh/parallel/threads.hpp"
#include "bench_common.hpp"
#include "bench_input.hpp"

using namespace keymesh;

KEYMESH_REEXEC_WITH_HUGE_PAGES_AT_START();

int main(int argc, char** argv) {
  bench::CommonOptions o;
  std::string weld = "keyreduce", normals = "none", grid_kind = "voxel";
  bool coarsen = false, scalars = false;
  std::vector<double> isos;
  const int status = bench::parse_options(argc, argv, o, [&](const std::string& a, const char* value) {
    if (a == "--weld") weld = value;
    else if (a == "--normals") normals = value;
    else if (a == "--iso") {
      // One isovalue, or several separated by commas (contoured in one call).
      isos.clear();
      for (std::string rest = value; !rest.empty();) {
        const auto comma = rest.find(',');
        isos.push_back(std::atof(rest.substr(0, comma).c_str()));
        rest = comma == std::string::npos ? "" : rest.substr(comma + 1);
      }
      o.iso = isos.empty() ? -1 : isos.front();
    }
    else if (a == "--grid") grid_kind = value;
    else if (a == "--coarsen") coarsen = std::string(value) == "on";
    else if (a == "--scalars") scalars = std::string(value) == "on";
    else return false;
    return true;
  });
  if (status != 0) return status;
  if (o.iso < 0) o.iso = bench::sphere_iso(o.size);
  const int used = parallel::set_thread_count(o.threads);
  if (grid_kind != "voxel" && grid_kind != "tet5") {
    std::fprintf(stderr, "--grid must be voxel or tet5\n");
    return 2;
  }
  const ImageGrid grid = bench::input_volume(o.file, o.size);
  UnstructuredGrid tets;
  double build = 0;
  if (grid_kind == "tet5") {
    const auto t0 = std::chrono::steady_clock::now();
    tets = generate::tetrahedralize5(grid);
    build = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  generate::ContourOptions opt;
  opt.isovalues = isos.size() > 1 ? isos : std::vector<double>{o.iso};
  opt.weld = weld == "vertexweld"       ? generate::ContourWeld::VertexWeld
             : weld == "keyreduce-sort" ? generate::ContourWeld::KeyReduceSort
                                        : generate::ContourWeld::KeyReduce;
  opt.normals = normals == "average"    ? generate::ContourNormals::Average
                : normals == "gradient" ? generate::ContourNormals::Gradient
                                        : generate::ContourNormals::None;
  opt.scalars = scalars;
  opt.coarsen = coarsen;
  std::vector<double> times;
  generate::ContourStats stats;
  Id points = 0, cells = 0;
  for (int r = 0; r < o.reps; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    const SurfaceMesh m = grid_kind == "tet5" ? generate::contour(tets, opt, &stats) : generate::contour(grid, opt, &stats);
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    points = m.num_points();
    cells = m.num_cells();
  }
  std::printf(
      "{\"bench\":\"contour\",\"grid\":\"%s\",\"build\":%.6f,\"size\":%lld,\"iso\":%.6f,\"weld\":\"%s\",\"normals\":\"%s\",\"threads\":%d,"
      "\"points\":%lld,\"cells\":%lld,%s,"
      "\"classify\":%.6f,\"generate\":%.6f,\"weld_s\":%.6f,\"fields\":%.6f,\"coarsen_s\":%.6f,\"peak_rss_mib\":%.1f}\n",
      grid_kind.c_str(), build, o.size, o.iso, weld.c_str(), normals.c_str(), used, (long long)points, (long long)cells,
      bench::timing_json(times).c_str(), stats.classify, stats.generate, stats.weld, stats.fields, stats.coarsen,
      bench::peak_rss_mib());
  return 0;
}
