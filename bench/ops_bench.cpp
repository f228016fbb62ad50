// Times the keyed operations beyond the contour in-process, on the paper's
// Spherical Distance field, for the paper's Tables 3 and 4. One JSON line:
//   ops_bench --op subdivide --size 256 --threads 2 --reps 5 [--weld keyreduce|vertexweld]
//             [--scheme linear|bezier]      triangles 1->4 of the sphere contour (iso N/2 - 1 + 0.001)
//   ops_bench --op tet24 --size 128 ...      face-centred tetrahedralization of the grid
//   ops_bench --op tet5  --size 256 ...      the minimal 5-tet split
//   ops_bench --op coarsen --size 256 ...    contour with coarsening (Table 5; compare --op contour)
//   ops_bench --op contour --size 256 ...    the same contour without it
//   ops_bench --op dual --size 256 ...       the dual of the sphere contour (Table 6)
//   ops_bench --op tetcontour --size 128 ... marching tetrahedra on the grid's 5-tet split
//   --file VOLUME --iso V: run the op on a volume file (read_volume) at that isovalue
//   instead of the sphere; "size" then reports the largest dimension.
// Memory columns (bench_memory.hpp): the op's input and output MiB, its
// peak in the first repetition (input + what it added) and over all of
// them, beside the process's peak_rss_mib.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "keymesh/core/huge_pages.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/unstructured/contour_tets.hpp"
#include "keymesh/generate/unstructured/dual.hpp"
#include "keymesh/generate/unstructured/subdivide.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"
#include "keymesh/parallel/threads.hpp"
#include "bench_common.hpp"
#include "bench_input.hpp"
#include "bench_memory.hpp"

using namespace keymesh;

KEYMESH_REEXEC_WITH_HUGE_PAGES_AT_START();

int main(int argc, char** argv) {
  bench::CommonOptions o;
  o.size = 128;
  std::string op = "subdivide", weld = "keyreduce", scheme = "linear";
  const int status = bench::parse_options(argc, argv, o, [&](const std::string& a, const char* value) {
    if (a == "--op") op = value;
    else if (a == "--weld") weld = value;
    else if (a == "--scheme") scheme = value;
    else return false;
    return true;
  });
  if (status != 0) return status;
  if (op != "subdivide" && op != "tet24" && op != "tet5" && op != "coarsen" && op != "contour" && op != "dual" &&
      op != "tetcontour") {
    std::fprintf(stderr, "--op must be subdivide, tet24, tet5, coarsen, contour, dual or tetcontour\n");
    return 2;
  }
  const int used = parallel::set_thread_count(o.threads);
  const ImageGrid grid = bench::input_volume(o.file, o.size);
  if (o.iso < 0) o.iso = bench::sphere_iso(o.size);
  SurfaceMesh surface;
  generate::ContourOptions contour_opt;
  contour_opt.isovalues = {o.iso};
  contour_opt.coarsen = op == "coarsen";
  if (op == "tetcontour") contour_opt.normals = generate::ContourNormals::Average;
  if (op == "subdivide" || op == "dual") {
    generate::ContourOptions c;
    c.isovalues = {o.iso};
    c.normals = generate::ContourNormals::Average;
    surface = generate::contour(grid, c);
  }
  UnstructuredGrid tets;
  if (op == "tetcontour") tets = generate::tetrahedralize5(grid);
  const double input_mib = bench::mib(op == "subdivide" || op == "dual" ? bench::bytes_of(surface)
                                : op == "tetcontour"                ? bench::bytes_of(tets)
                                                                    : bench::bytes_of(grid));
  double output_mib = 0;
  generate::SubdivideOptions so;
  so.scheme = scheme == "bezier" ? generate::SubdivideScheme::Bezier : generate::SubdivideScheme::Linear;
  so.weld = weld == "vertexweld" ? generate::SubdivideWeld::VertexWeld : generate::SubdivideWeld::KeyReduce;
  std::vector<double> times;
  Id points = 0, cells = 0;
  const bench::PeakWindow window;
  double first_added_mib = 0;
  for (int r = 0; r < o.reps; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    if (op == "subdivide") {
      const SurfaceMesh m = generate::subdivide(surface, so);
      points = m.num_points(), cells = m.num_cells();
      output_mib = bench::mib(bench::bytes_of(m));
    } else if (op == "dual") {
      const SurfaceMesh m = generate::dual(surface);
      points = m.num_points(), cells = m.num_cells();
      output_mib = bench::mib(bench::bytes_of(m));
    } else if (op == "coarsen" || op == "contour") {
      const SurfaceMesh m = generate::contour(grid, contour_opt);
      points = m.num_points(), cells = m.num_cells();
      output_mib = bench::mib(bench::bytes_of(m));
    } else if (op == "tetcontour") {
      const SurfaceMesh m = generate::contour(tets, contour_opt);
      points = m.num_points(), cells = m.num_cells();
      output_mib = bench::mib(bench::bytes_of(m));
    } else {
      const UnstructuredGrid g =
          op == "tet24" ? generate::tetrahedralize24(grid, weld == "vertexweld") : generate::tetrahedralize5(grid);
      points = g.num_points(), cells = g.num_cells();
      output_mib = bench::mib(bench::bytes_of(g));
    }
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    if (r == 0) first_added_mib = window.added_mib();
  }
  std::printf(
      "{\"bench\":\"%s\",\"size\":%lld,\"iso\":%.6f,\"weld\":\"%s\",\"scheme\":\"%s\",\"threads\":%d,\"input_points\":%lld,"
      "\"input_cells\":%lld,\"points\":%lld,\"cells\":%lld,%s,\"peak_rss_mib\":%.1f,%s}\n",
      op.c_str(), o.size, o.iso, weld.c_str(), scheme.c_str(), used, (long long)surface.num_points(),
      (long long)surface.num_cells(), (long long)points, (long long)cells, bench::timing_json(times).c_str(),
      bench::peak_rss_mib(), bench::memory_json(input_mib, output_mib, first_added_mib, window.added_mib()).c_str());
  return 0;
}
