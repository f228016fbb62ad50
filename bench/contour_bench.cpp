// Times marching cubes + weld on the Spherical Distance field in-process (no
// file I/O), for the paper's Table 2 rows. Prints one JSON line per case:
//   contour_bench --size 512 --threads 2 --reps 5
//                 [--weld keyreduce|keyreduce-sort|vertexweld]
//                 [--normals none|gradient|average] [--iso V] [--grid voxel|tet5]
//                 [--file VOLUME] [--iso V1,V2,...] [--coarsen on]
// --file contours a volume file (any format keymesh::io::read_volume reads:
// .vti .nrrd .nii(.gz) .den) instead of generating the sphere; --iso is then
// required and "size" reports the largest dimension.
// --grid tet5 contours the scheme-5 tetrahedralization of the field by
// marching tetrahedra; the tetrahedralization is timed once ("build").
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "keymesh/core/huge_pages.hpp"
#include "keymesh/generate/contour.hpp"
#include "keymesh/generate/contour_tets.hpp"
#include "keymesh/generate/tetrahedralize.hpp"
#include "keymesh/parallel/threads.hpp"
#include "bench_input.hpp"

using namespace keymesh;

int main(int argc, char** argv) {
  reexec_with_huge_pages(argc, argv);
  long long size = 256;
  int threads = 0, reps = 5;
  std::string weld = "keyreduce", normals = "none", grid_kind = "voxel", file;
  double iso = -1;
  bool coarsen = false;
  std::vector<double> isos;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--size") size = std::atoll(argv[i + 1]);
    else if (a == "--threads") threads = std::atoi(argv[i + 1]);
    else if (a == "--reps") reps = std::atoi(argv[i + 1]);
    else if (a == "--weld") weld = argv[i + 1];
    else if (a == "--normals") normals = argv[i + 1];
    else if (a == "--iso") {
      // One isovalue, or several separated by commas (contoured in one call).
      isos.clear();
      for (std::string rest = argv[i + 1]; !rest.empty();) {
        const auto comma = rest.find(',');
        isos.push_back(std::atof(rest.substr(0, comma).c_str()));
        rest = comma == std::string::npos ? "" : rest.substr(comma + 1);
      }
      iso = isos.empty() ? -1 : isos.front();
    }
    else if (a == "--grid") grid_kind = argv[i + 1];
    else if (a == "--file") file = argv[i + 1];
    else if (a == "--coarsen") coarsen = std::string(argv[i + 1]) == "on";
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  if (!file.empty() && iso < 0) {
    std::fprintf(stderr, "--file needs --iso\n");
    return 2;
  }
  if (iso < 0) iso = static_cast<double>(size / 2) - 1 + 0.001;
  const int used = parallel::set_thread_count(threads);
  if (grid_kind != "voxel" && grid_kind != "tet5") {
    std::fprintf(stderr, "--grid must be voxel or tet5\n");
    return 2;
  }
  const ImageGrid grid = bench::input_volume(file, size);
  UnstructuredGrid tets;
  double build = 0;
  if (grid_kind == "tet5") {
    const auto t0 = std::chrono::steady_clock::now();
    tets = generate::tetrahedralize5(grid);
    build = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  generate::ContourOptions opt;
  opt.isovalues = isos.size() > 1 ? isos : std::vector<double>{iso};
  opt.weld = weld == "vertexweld"       ? generate::ContourWeld::VertexWeld
             : weld == "keyreduce-sort" ? generate::ContourWeld::KeyReduceSort
                                        : generate::ContourWeld::KeyReduce;
  opt.normals = normals == "average"    ? generate::ContourNormals::Average
                : normals == "gradient" ? generate::ContourNormals::Gradient
                                        : generate::ContourNormals::None;
  opt.scalars = false;
  opt.coarsen = coarsen;
  std::vector<double> times;
  generate::ContourStats stats;
  Id points = 0, cells = 0;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    const SurfaceMesh m = grid_kind == "tet5" ? generate::contour(tets, opt, &stats) : generate::contour(grid, opt, &stats);
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    points = m.num_points();
    cells = m.num_cells();
  }
  const double first = times.front();  // the cold run: fresh memory, as in a one-shot CLI
  std::sort(times.begin(), times.end());
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::printf(
      "{\"bench\":\"contour\",\"grid\":\"%s\",\"build\":%.6f,\"size\":%lld,\"iso\":%.6f,\"weld\":\"%s\",\"normals\":\"%s\",\"threads\":%d,"
      "\"points\":%lld,\"cells\":%lld,\"median\":%.6f,\"min\":%.6f,\"max\":%.6f,\"first\":%.6f,\"reps\":%d,"
      "\"classify\":%.6f,\"generate\":%.6f,\"weld_s\":%.6f,\"fields\":%.6f,\"coarsen_s\":%.6f,\"peak_rss_mib\":%.1f}\n",
      grid_kind.c_str(), build, size, iso, weld.c_str(), normals.c_str(), used, (long long)points, (long long)cells, times[times.size() / 2],
      times.front(), times.back(), first, reps, stats.classify, stats.generate, stats.weld, stats.fields, stats.coarsen,
      static_cast<double>(usage.ru_maxrss) / 1024.0);
  return 0;
}
