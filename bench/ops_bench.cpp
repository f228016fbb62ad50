// Times the keyed operations beyond the contour in-process, on the paper's
// Spherical Distance field, for the paper's Tables 3 and 4. One JSON line:
//   ops_bench --op subdivide --size 256 --threads 2 --reps 5 [--weld keyreduce|vertexweld]
//             [--scheme linear|bezier]      triangles 1->4 of the sphere contour (iso N/2 - 1 + 0.001)
//   ops_bench --op tet24 --size 128 ...      face-centred tetrahedralization of the grid
//   ops_bench --op tet5  --size 256 ...      the minimal 5-tet split
//   ops_bench --op coarsen --size 256 ...    contour with coarsening (Table 5; compare --op contour)
//   ops_bench --op contour --size 256 ...    the same contour without it
//   ops_bench --op dual --size 256 ...       the dual of the sphere contour (Table 6)
//   --file VOLUME --iso V: run the op on a volume file (read_volume) at that isovalue
//   instead of the sphere; "size" then reports the largest dimension.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "keymesh/core/huge_pages.hpp"
#include "keymesh/generate/contour.hpp"
#include "keymesh/generate/dual.hpp"
#include "keymesh/generate/subdivide.hpp"
#include "keymesh/generate/tetrahedralize.hpp"
#include "keymesh/parallel/threads.hpp"
#include "bench_input.hpp"

using namespace keymesh;

int main(int argc, char** argv) {
  reexec_with_huge_pages(argc, argv);
  long long size = 128;
  int threads = 0, reps = 5;
  std::string op = "subdivide", weld = "keyreduce", scheme = "linear", file;
  double iso = -1;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--size") size = std::atoll(argv[i + 1]);
    else if (a == "--threads") threads = std::atoi(argv[i + 1]);
    else if (a == "--reps") reps = std::atoi(argv[i + 1]);
    else if (a == "--op") op = argv[i + 1];
    else if (a == "--weld") weld = argv[i + 1];
    else if (a == "--scheme") scheme = argv[i + 1];
    else if (a == "--file") file = argv[i + 1];
    else if (a == "--iso") iso = std::atof(argv[i + 1]);
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  if (op != "subdivide" && op != "tet24" && op != "tet5" && op != "coarsen" && op != "contour" && op != "dual") {
    std::fprintf(stderr, "--op must be subdivide, tet24, tet5, coarsen, contour or dual\n");
    return 2;
  }
  const int used = parallel::set_thread_count(threads);
  if (!file.empty() && iso < 0) {
    std::fprintf(stderr, "--file needs --iso\n");
    return 2;
  }
  const ImageGrid grid = bench::input_volume(file, size);
  if (iso < 0) iso = static_cast<double>(size / 2) - 1 + 0.001;
  SurfaceMesh surface;
  generate::ContourOptions contour_opt;
  contour_opt.isovalues = {iso};
  contour_opt.coarsen = op == "coarsen";
  if (op == "subdivide" || op == "dual") {
    generate::ContourOptions c;
    c.isovalues = {iso};
    c.normals = generate::ContourNormals::Average;
    surface = generate::contour(grid, c);
  }
  generate::SubdivideOptions so;
  so.scheme = scheme == "bezier" ? generate::SubdivideScheme::Bezier : generate::SubdivideScheme::Linear;
  so.weld = weld == "vertexweld" ? generate::SubdivideWeld::VertexWeld : generate::SubdivideWeld::KeyReduce;
  std::vector<double> times;
  Id points = 0, cells = 0;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    if (op == "subdivide") {
      const SurfaceMesh m = generate::subdivide(surface, so);
      points = m.num_points(), cells = m.num_cells();
    } else if (op == "dual") {
      const SurfaceMesh m = generate::dual(surface);
      points = m.num_points(), cells = m.num_cells();
    } else if (op == "coarsen" || op == "contour") {
      const SurfaceMesh m = generate::contour(grid, contour_opt);
      points = m.num_points(), cells = m.num_cells();
    } else {
      const UnstructuredGrid g =
          op == "tet24" ? generate::tetrahedralize24(grid, weld == "vertexweld") : generate::tetrahedralize5(grid);
      points = g.num_points(), cells = g.num_cells();
    }
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  const double first = times.front();
  std::sort(times.begin(), times.end());
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::printf(
      "{\"bench\":\"%s\",\"size\":%lld,\"iso\":%.6f,\"weld\":\"%s\",\"scheme\":\"%s\",\"threads\":%d,\"input_points\":%lld,"
      "\"input_cells\":%lld,\"points\":%lld,\"cells\":%lld,\"median\":%.6f,\"min\":%.6f,\"max\":%.6f,\"first\":%.6f,"
      "\"reps\":%d,\"peak_rss_mib\":%.1f}\n",
      op.c_str(), size, iso, weld.c_str(), scheme.c_str(), used, (long long)surface.num_points(),
      (long long)surface.num_cells(), (long long)points, (long long)cells, times[times.size() / 2], times.front(),
      times.back(), first, reps, static_cast<double>(usage.ru_maxrss) / 1024.0);
  return 0;
}
