// Streaming a volume larger than memory: contour a PlaneSource slab by slab.
//
//   PlaneSource: planes z = first .. first+count        contour_streamed: slabs of planes that
//   computed (or read) on demand; the whole volume  ->  fit the memory limit, each contoured
//   never exists                                        with the whole grid's edge keys; one
//                                                       KEY-REDUCE merges the planes they share
//
// The streamed surface is the in-memory contour byte for byte (same keys, same point order).
// The CLI does the same with `keymesh contour VOLUME --memory-limit 512M`, reading raw, NRRD,
// NIfTI, Zarr or DICOM planes (io::open_volume_planes).
#include <cmath>
#include <cstdio>
#include <cstring>

#include "keymesh/analyze/topology.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/contour/contour_stream.hpp"
#include "keymesh/mesh/plane_source.hpp"

#include "expect.hpp"

using namespace keymesh;

// A torus' distance field, computed a plane at a time: each sample is its
// distance (in voxels) from a circle of radius 24 around the grid's centre.
class TorusPlanes : public PlaneSource {
 public:
  TorusPlanes() {
    header_.dims = {96, 96, 64};
    header_.type = ScalarType::Float32;
    header_.name = "distance";
  }
  const ImageGrid& header() const override { return header_; }
  void read_planes(Id first, Id count, std::byte* out) override {
    const Id nx = header_.dims[0], ny = header_.dims[1];
    float* sample = reinterpret_cast<float*>(out);
    for (Id k = first; k < first + count; ++k)
      for (Id j = 0; j < ny; ++j)
        for (Id i = 0; i < nx; ++i) {
          const float x = float(i) - 47.5f, y = float(j) - 47.5f, z = float(k) - 31.5f;
          *sample++ = std::hypot(std::hypot(x, y) - 24.0f, z);
        }
    planes_read += count;
  }
  Id planes_read = 0;

 private:
  ImageGrid header_;
};

static bool same_bytes(const Array<float>& a, const Array<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

int main() {
  TorusPlanes source;
  generate::ContourOptions options;
  options.isovalues = {10.5};
  options.normals = generate::ContourNormals::Gradient;  // central differences: slabs read a ghost plane each side
  const std::size_t limit = 16 * 96 * 96 * sizeof(float);  // 16 planes of samples at a time (576 KiB)
  generate::StreamStats stream;
  const SurfaceMesh streamed = generate::contour_streamed(source, options, limit, nullptr, &stream);
  std::printf("%lld slabs of %lld planes (%zu bytes of samples at once, %lld planes read): %lld points\n",
              static_cast<long long>(stream.slabs), static_cast<long long>(stream.planes_per_slab),
              stream.slab_bytes, static_cast<long long>(source.planes_read),
              static_cast<long long>(streamed.num_points()));
  EXPECT(stream.slabs >= 4);
  EXPECT(stream.slab_bytes <= limit);

  const analyze::TopologyReport topology = analyze::check_topology(streamed);
  EXPECT(topology.closed_manifold);
  EXPECT(topology.euler_characteristic == 0);  // a torus

  // The check only: the whole volume in memory, contoured at once, gives the same bytes.
  ImageGrid whole = source.header();
  whole.allocate(whole.dims, whole.type);
  source.read_planes(0, whole.dims[2], whole.bytes.data());
  const SurfaceMesh in_memory = generate::contour(whole, options);
  EXPECT(same_bytes(streamed.points, in_memory.points));
  EXPECT(streamed.connectivity == in_memory.connectivity);
  EXPECT(streamed.point_fields.size() == in_memory.point_fields.size());
  for (std::size_t f = 0; f < streamed.point_fields.size(); ++f)
    EXPECT(same_bytes(streamed.point_fields[f].values, in_memory.point_fields[f].values));
  return 0;
}
