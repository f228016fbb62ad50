// Peer: Bell's Thrust VERTEX-WELD (the paper's [Bel10] baseline) on Thrust's
// OpenMP host backend, for bench/run.py. One JSON line:
//   thrust_weld --size 256 --threads 2 --reps 5            the Spherical Distance field
//   thrust_weld --file VOLUME --iso V --threads 2 --reps 5 a volume file
//
// The triangle soup is what marching cubes writes: a position per triangle
// corner. It is rebuilt here from keymesh's welded contour (each triangle's
// three corners expanded to their positions), which is exactly the soup
// keymesh's own VERTEX-WELD welds. Only the weld is timed, as in Bell's
// example: copy the soup, sort the positions lexicographically, unique, then
// lower_bound every corner to get the connectivity.
#include <thrust/binary_search.h>
#include <thrust/device_vector.h>
#include <thrust/sort.h>
#include <thrust/tuple.h>
#include <thrust/unique.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <omp.h>

#include "keymesh/core/huge_pages.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/parallel/threads.hpp"
#include "../bench_common.hpp"
#include "../bench_input.hpp"

using namespace keymesh;

namespace {
struct Pos {
  float x, y, z;
};
struct Less {
  __host__ __device__ bool operator()(const Pos& a, const Pos& b) const {
    if (a.x != b.x) return a.x < b.x;
    if (a.y != b.y) return a.y < b.y;
    return a.z < b.z;
  }
};
struct Equal {
  __host__ __device__ bool operator()(const Pos& a, const Pos& b) const {
    return a.x == b.x && a.y == b.y && a.z == b.z;
  }
};
}  // namespace

KEYMESH_REEXEC_WITH_HUGE_PAGES_AT_START();

int main(int argc, char** argv) {
  bench::CommonOptions o;
  const int status = bench::parse_options(argc, argv, o, [](const std::string&, const char*) { return false; });
  if (status != 0) return status;
  const int used = parallel::set_thread_count(o.threads);
  omp_set_num_threads(used);
  std::vector<float> soup;
  {
    const ImageGrid grid = bench::input_volume(o.file, o.size);
    if (o.iso < 0) o.iso = bench::sphere_iso(o.size);
    generate::ContourOptions opt;
    opt.isovalues = {o.iso};
    opt.scalars = false;
    const SurfaceMesh m = generate::contour(grid, opt);
    soup.resize(m.connectivity.size() * 3);
    for (std::size_t c = 0; c < m.connectivity.size(); ++c)
      for (int d = 0; d < 3; ++d) soup[3 * c + d] = m.points[3 * std::size_t(m.connectivity[c]) + d];
  }
  const std::size_t corners = soup.size() / 3;
  const Pos* soup_pos = reinterpret_cast<const Pos*>(soup.data());
  std::vector<double> times;
  std::size_t points = 0;
  for (int r = 0; r < o.reps; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    thrust::device_vector<Pos> vertices(soup_pos, soup_pos + corners);
    thrust::device_vector<Pos> input(vertices);
    thrust::sort(vertices.begin(), vertices.end(), Less());
    vertices.erase(thrust::unique(vertices.begin(), vertices.end(), Equal()), vertices.end());
    thrust::device_vector<unsigned> indices(corners);
    thrust::lower_bound(vertices.begin(), vertices.end(), input.begin(), input.end(), indices.begin(), Less());
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    points = vertices.size();
  }
  std::printf(
      "{\"bench\":\"contour\",\"tool\":\"thrust-vertexweld\",\"backend\":\"thrust-omp-%d.%d.%d\",\"grid\":\"voxel\","
      "\"size\":%lld,\"iso\":%.6f,\"threads\":%d,\"soup_points\":%zu,\"points\":%zu,\"cells\":%zu,%s,"
      "\"peak_rss_mib\":%.1f}\n",
      THRUST_MAJOR_VERSION, THRUST_MINOR_VERSION, THRUST_SUBMINOR_VERSION, o.size, o.iso, used, corners, points,
      corners / 3, bench::timing_json(times).c_str(), bench::peak_rss_mib());
  return 0;
}
