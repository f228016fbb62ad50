// keymesh_gpu_timing: the GPU check's in-process measurements
// (scripts/gpu_check.sh, docs/gpu-check.md). One JSON object per line on stdout.
//
//   keymesh_gpu_timing sphere N [--repeat R] [--warmup W] [--no-cpu]
//     The Spherical Distance field N^3 contoured at the paper's Table 1
//     isovalue N/2 - 1 + 0.001 on the GPU: W warm-up runs, then R runs, each
//     timed with CUDA events on the legacy default stream (cuda::contour's
//     stream waits for it and is synchronized before it returns, so the
//     events bracket the upload, every stage and the download), the median
//     and the minimum reported with the last run's stage times. Then the same
//     with device-resident input (cuda::contour_device: the samples uploaded
//     once, the mesh left on the device), its median and minimum, its mesh
//     compared with the host path's. Unless --no-cpu, the CPU's mesh is made
//     once and compared bit for bit.
//   keymesh_gpu_timing checkerboard N
//     A uint8 checkerboard N^3 at 127.5: every voxel holds 4 triangles, so
//     past N = 1025 the output passes 2^32 triangles. The GPU must refuse it
//     (LimitError) as the CPU does, or make the CPU's mesh: exit 0 when refused.
//
// Exit status: 0 when every comparison held, 1 when one did not, 2 on bad
// arguments or an unexpected error (its message on stderr).
#include <cuda_runtime.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "keymesh/backend/contour.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/cuda/backend.hpp"
#include "keymesh/cuda/device_contour.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/spherical_distance.hpp"

using namespace keymesh;

namespace {

struct Args {
  std::string what;
  Id n = 0;
  int repeat = 5, warmup = 1;
  bool cpu = true;
};

Args parse(int argc, char** argv) {
  Args a;
  if (argc < 3)
    throw InputError("usage: keymesh_gpu_timing sphere|checkerboard N [--repeat R] [--warmup W] [--no-cpu]");
  a.what = argv[1];
  a.n = std::stoll(argv[2]);
  for (int i = 3; i < argc; ++i) {
    const std::string o = argv[i];
    if (o == "--no-cpu")
      a.cpu = false;
    else if ((o == "--repeat" || o == "--warmup") && i + 1 < argc)
      (o == "--repeat" ? a.repeat : a.warmup) = std::stoi(argv[++i]);
    else
      throw InputError("unknown option " + o);
  }
  if ((a.what != "sphere" && a.what != "checkerboard") || a.n < 2 || a.repeat < 1 || a.warmup < 0)
    throw InputError("sphere|checkerboard N (N >= 2), --repeat >= 1, --warmup >= 0");
  return a;
}

bool same_bits(const Array<float>& a, const Array<float>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

bool identical(const SurfaceMesh& a, const SurfaceMesh& b) {
  if (!same_bits(a.points, b.points) || a.connectivity.size() != b.connectivity.size()) return false;
  if (!a.connectivity.empty() &&
      std::memcmp(a.connectivity.data(), b.connectivity.data(), a.connectivity.size() * sizeof(a.connectivity[0])))
    return false;
  if (a.point_fields.size() != b.point_fields.size()) return false;
  for (std::size_t i = 0; i < a.point_fields.size(); ++i)
    if (a.point_fields[i].name != b.point_fields[i].name ||
        !same_bits(a.point_fields[i].values, b.point_fields[i].values))
      return false;
  return true;
}

void check_cuda(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw InputError(std::string(what) + ": " + cudaGetErrorString(e));
}

// run() timed with CUDA events on the default stream, in milliseconds.
template <class Run>
double gpu_milliseconds(Run&& run) {
  cudaEvent_t start, stop;
  check_cuda(cudaEventCreate(&start), "creating an event");
  check_cuda(cudaEventCreate(&stop), "creating an event");
  check_cuda(cudaEventRecord(start, 0), "recording an event");
  run();
  check_cuda(cudaEventRecord(stop, 0), "recording an event");
  check_cuda(cudaEventSynchronize(stop), "waiting for an event");
  float ms = 0;
  check_cuda(cudaEventElapsedTime(&ms, start, stop), "reading an event");
  cudaEventDestroy(start);
  cudaEventDestroy(stop);
  return ms;
}

// One GPU contour timed with CUDA events, in milliseconds.
double timed_gpu_contour(const ImageGrid& g, const generate::ContourOptions& o, SurfaceMesh& mesh,
                         generate::ContourStats& st) {
  return gpu_milliseconds([&] { mesh = backend::contour(g, o, &st); });
}

// A device mesh downloaded, for the comparison with the CPU's.
SurfaceMesh downloaded(const cuda::DeviceMesh& m) {
  SurfaceMesh mesh;
  mesh.points.resize(static_cast<std::size_t>(3 * m.points));
  mesh.connectivity.resize(static_cast<std::size_t>(3 * m.triangles));
  auto copy = [](void* to, const cuda::DeviceBuffer& from, std::size_t bytes) {
    if (bytes) check_cuda(cudaMemcpy(to, from.get(), bytes, cudaMemcpyDeviceToHost), "downloading the mesh");
  };
  copy(mesh.points.data(), m.xyz, mesh.points.size() * sizeof(float));
  copy(mesh.connectivity.data(), m.connectivity, mesh.connectivity.size() * sizeof(mesh.connectivity[0]));
  for (const cuda::DeviceField& f : m.point_fields) {
    Field field{f.name, f.components, Array<float>(static_cast<std::size_t>(m.points * f.components))};
    copy(field.values.data(), f.values, field.values.size() * sizeof(float));
    mesh.point_fields.push_back(std::move(field));
  }
  return mesh;
}

// Device-resident input (cuda::contour_device): the samples uploaded once,
// each run timed with CUDA events from the samples on the device to the mesh
// on the device (no upload, no download). Adds its keys to js; returns
// whether the last run's mesh is the host path's `gpu`, bit for bit.
bool device_input_runs(const ImageGrid& g, const generate::ContourOptions& o, const Args& a, const SurfaceMesh& gpu,
                       std::ostringstream& js) {
  void* samples = nullptr;
  check_cuda(cudaMalloc(&samples, g.bytes.size()), "allocating the samples");
  check_cuda(cudaMemcpy(samples, g.bytes.data(), g.bytes.size(), cudaMemcpyHostToDevice), "uploading the samples");
  cuda::DeviceVolume v;
  v.grid.dims = g.dims, v.grid.type = g.type, v.grid.name = g.name;
  v.samples = samples;
  cuda::DeviceMesh mesh;
  std::vector<double> runs;
  for (int i = 0; i < a.warmup + a.repeat; ++i) {
    mesh = cuda::DeviceMesh{};  // the previous mesh freed before the run
    const double ms = gpu_milliseconds([&] { mesh = cuda::contour_device(v, o); });
    if (i >= a.warmup) runs.push_back(ms);
  }
  const bool same = identical(downloaded(mesh), gpu);
  mesh = cuda::DeviceMesh{};
  cudaFree(samples);
  std::sort(runs.begin(), runs.end());
  js << ", \"device_input_ms_median\": " << runs[runs.size() / 2] << ", \"device_input_ms_min\": " << runs.front()
     << ", \"device_input_identical\": " << (same ? "true" : "false");
  return same;
}

int sphere(const Args& a) {
  const ImageGrid g = generate::spherical_distance(a.n);
  generate::ContourOptions o;
  o.isovalues = {double(a.n) / 2 - 1 + 0.001};
  o.backend = generate::Backend::Cuda;
  SurfaceMesh gpu;
  generate::ContourStats st;
  for (int i = 0; i < a.warmup; ++i) timed_gpu_contour(g, o, gpu, st);
  std::vector<double> runs;
  for (int i = 0; i < a.repeat; ++i) runs.push_back(timed_gpu_contour(g, o, gpu, st));
  std::vector<double> sorted = runs;
  std::sort(sorted.begin(), sorted.end());
  std::ostringstream js;
  js << "{\"case\": \"sphere\", \"size\": " << a.n << ", \"points\": " << gpu.num_points()
     << ", \"triangles\": " << gpu.num_cells() << ", \"gpu_ms_median\": " << sorted[sorted.size() / 2]
     << ", \"gpu_ms_min\": " << sorted.front() << ", \"gpu_ms_runs\": [";
  for (std::size_t i = 0; i < runs.size(); ++i) js << (i ? ", " : "") << runs[i];
  js << "], \"stage_ms\": {\"classify\": " << 1e3 * st.classify << ", \"generate\": " << 1e3 * st.generate << ", \"weld\": " << 1e3 * st.weld
     << ", \"fields\": " << 1e3 * st.fields << "}, \"device_peak_bytes\": " << st.device_peak_bytes;
  bool ok = device_input_runs(g, o, a, gpu, js);
  if (a.cpu) {
    o.backend = generate::Backend::Cpu;
    const auto t0 = std::chrono::steady_clock::now();
    const SurfaceMesh cpu = generate::contour(g, o);
    js << ", \"cpu_ms\": " << 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ok = identical(cpu, gpu) && ok;
    js << ", \"identical_to_cpu\": " << (ok ? "true" : "false");
  }
  std::cout << js.str() << "}" << std::endl;
  return ok ? 0 : 1;
}

int checkerboard(const Args& a) {
  ImageGrid g;
  g.allocate({a.n, a.n, a.n}, ScalarType::UInt8);
  auto* v = static_cast<std::uint8_t*>(g.data());
  for (Id k = 0; k < a.n; ++k)
    for (Id j = 0; j < a.n; ++j)
      for (Id i = 0; i < a.n; ++i) v[i + a.n * (j + a.n * k)] = ((i + j + k) & 1) ? 255 : 0;
  generate::ContourOptions o;
  o.isovalues = {127.5};
  o.scalars = false;
  o.backend = generate::Backend::Cuda;
  std::ostringstream js;
  js << "{\"case\": \"checkerboard\", \"size\": " << a.n
     << ", \"expected_triangles\": " << 4 * (a.n - 1) * (a.n - 1) * (a.n - 1);
  int rc = 0;
  try {
    const SurfaceMesh gpu = backend::contour(g, o);
    js << ", \"refused\": false, \"triangles\": " << gpu.num_cells();
    rc = gpu.num_cells() == 4 * (a.n - 1) * (a.n - 1) * (a.n - 1) ? 0 : 1;
  } catch (const LimitError& e) {
    std::string m = e.what();
    std::replace(m.begin(), m.end(), '"', '\'');
    js << ", \"refused\": true, \"error\": \"" << m << "\"";
  }
  std::cout << js.str() << "}" << std::endl;
  return rc;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && std::string(argv[1]) == "--help") {
    std::cout << "keymesh_gpu_timing sphere|checkerboard N [--repeat R] [--warmup W] [--no-cpu] "
                 "(tests/cuda/gpu_timing.cpp)\n";
    return 0;
  }
  try {
    const Args a = parse(argc, argv);
    std::string why;
    if (!cuda::available(&why)) {
      std::cout << "{\"case\": \"" << a.what << "\", \"skipped\": \"no GPU: " << why << "\"}" << std::endl;
      return 0;
    }
    return a.what == "sphere" ? sphere(a) : checkerboard(a);
  } catch (const std::exception& e) {
    std::cerr << "keymesh_gpu_timing: " << e.what() << "\n";
    return 2;
  }
}
