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
// --peer fe3d also runs vtkFlyingEdges3D on the same samples in this process,
// at the same thread count, and adds "peer",
// "peer_median", "peer_min", "peer_max", "peer_first", "peer_reps", "peer_points",
// "peer_cells", "peer_ratio" (the peer's median over keymesh's) and
// "peak_rss_mib_with_peer" to the line ("times_ms" and "peer_times_ms": every
// call's milliseconds, in run order); "peak_rss_mib" is then taken after
// keymesh's first call, before the peer's first. --peer-order blocks (the
// default): half the repetitions of keymesh, half of the peer's, then the
// rest of each; turns: a call of each in turn (the first of a pair
// alternating). In turns, each tool's call follows the other's, whose
// threads may still spin (libgomp's, TBB's) on the second core: inia19
// (168x206x128 float32), 2 threads, keymesh's classify 0.4 ms alone and 1.0
// ms in turns. Only in a build with VTK's C++ package (libvtk9-dev); refused by
// name otherwise, and with --grid tet5.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "keymesh/core/huge_pages.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/unstructured/contour_tets.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"
#include "keymesh/parallel/threads.hpp"
#include "bench_common.hpp"
#include "bench_input.hpp"
#ifdef KEYMESH_BENCH_VTK
#include "peers/flying_edges_peer.hpp"
#endif

using namespace keymesh;

KEYMESH_REEXEC_WITH_HUGE_PAGES_AT_START();

int main(int argc, char** argv) {
  bench::CommonOptions o;
  std::string weld = "keyreduce", normals = "none", grid_kind = "voxel", peer, peer_order = "blocks";
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
    else if (a == "--peer") peer = value;
    else if (a == "--peer-order") peer_order = value;
    else return false;
    return true;
  });
  if (status != 0) return status;
  if (o.iso < 0) o.iso = bench::sphere_iso(o.size);
  const int used = parallel::set_thread_count(o.threads);
#ifdef KEYMESH_BENCH_VTK
  constexpr bool with_vtk = true;
#else
  constexpr bool with_vtk = false;
#endif
  // Options refused by name, exit status 2, before the volume is read.
  const std::pair<bool, const char*> refused[] = {
      {grid_kind != "voxel" && grid_kind != "tet5", "--grid must be voxel or tet5"},
      {!peer.empty() && peer != "fe3d", "--peer must be fe3d"},
      {peer_order != "blocks" && peer_order != "turns", "--peer-order must be blocks or turns"},
      {!peer.empty() && grid_kind != "voxel", "--peer fe3d contours the voxel grid only"},
      {!peer.empty() && !with_vtk,
       "--peer fe3d: this contour_bench was built without VTK's C++ package (libvtk9-dev)"},
  };
  for (const auto& [bad, why] : refused)
    if (bad) {
      std::fprintf(stderr, "%s\n", why);
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
  std::vector<double> times, peer_times;
  generate::ContourStats stats;
  Id points = 0, cells = 0;
  long long peer_points = 0, peer_cells = 0;
  double own_peak_rss = 0;  // after keymesh's first call, before any of the peer's
#ifdef KEYMESH_BENCH_VTK
  std::unique_ptr<bench::FlyingEdgesPeer> fe3d;
  if (!peer.empty()) fe3d = std::make_unique<bench::FlyingEdgesPeer>(grid, used);
#endif
  auto run_keymesh = [&] {
    const auto t0 = std::chrono::steady_clock::now();
    const SurfaceMesh m =
        grid_kind == "tet5" ? generate::contour(tets, opt, &stats) : generate::contour(grid, opt, &stats);
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    points = m.num_points();
    cells = m.num_cells();
    // keymesh's first call comes before any of the peer's: the peak RSS
    // taken after it is keymesh's. The mesh goes before the next call.
    if (times.size() == 1) own_peak_rss = bench::peak_rss_mib();
  };
  // The order of the calls: 'k' keymesh, 'p' the peer.
  std::string order;
  if (peer.empty()) {
    order.assign(static_cast<std::size_t>(o.reps), 'k');
  } else if (peer_order == "turns") {
    for (int r = 0; r < o.reps; ++r) order += r % 2 ? "pk" : "kp";
  } else {
    const int half = (o.reps + 1) / 2;
    order = std::string(static_cast<std::size_t>(half), 'k') + std::string(static_cast<std::size_t>(half), 'p') +
            std::string(static_cast<std::size_t>(o.reps - half), 'k') +
            std::string(static_cast<std::size_t>(o.reps - half), 'p');
  }
  for (const char c : order) {
    if (c == 'k') run_keymesh();
#ifdef KEYMESH_BENCH_VTK
    if (c == 'p') {
      const bench::FlyingEdgesPeer::Run p = fe3d->run(opt.isovalues, scalars);
      peer_times.push_back(p.seconds);
      peer_points = p.points;
      peer_cells = p.cells;
    }
#endif
  }
  // The peer's columns, and every call's milliseconds: the line's end.
  std::string extra_json;
  if (!peer_times.empty()) {
    char text[200];
    std::snprintf(text, sizeof text,
                  ",\"peer\":\"vtkFlyingEdges3D\",\"peer_points\":%lld,\"peer_cells\":%lld,\"peer_ratio\":%.4f,"
                  "\"peak_rss_mib_with_peer\":%.1f,",
                  peer_points, peer_cells, bench::median(peer_times) / bench::median(times), bench::peak_rss_mib());
    extra_json = text + bench::timing_json(peer_times, "peer_");
  }
  // Every call's milliseconds in run order (keymesh's, then the peer's):
  // which calls of a process were slow.
  auto list = [](const std::vector<double>& t) {
    std::string out = "[";
    for (std::size_t i = 0; i < t.size(); ++i) {
      char v[32];
      std::snprintf(v, sizeof v, "%s%.3f", i ? "," : "", t[i] * 1e3);
      out += v;
    }
    return out + "]";
  };
  extra_json += ",\"times_ms\":" + list(times);
  if (!peer_times.empty()) extra_json += ",\"peer_times_ms\":" + list(peer_times);
  std::printf(
      "{\"bench\":\"contour\",\"grid\":\"%s\",\"build\":%.6f,\"size\":%lld,\"iso\":%.6f,\"weld\":\"%s\",\"normals\":\"%s\",\"threads\":%d,"
      "\"points\":%lld,\"cells\":%lld,%s,"
      "\"classify\":%.6f,\"generate\":%.6f,\"weld_s\":%.6f,\"fields\":%.6f,\"coarsen_s\":%.6f,\"peak_rss_mib\":%.1f%s}\n",
      grid_kind.c_str(), build, o.size, o.iso, weld.c_str(), normals.c_str(), used, (long long)points, (long long)cells,
      bench::timing_json(times).c_str(), stats.classify, stats.generate, stats.weld, stats.fields, stats.coarsen,
      peer_times.empty() ? bench::peak_rss_mib() : own_peak_rss, extra_json.c_str());
  return 0;
}
