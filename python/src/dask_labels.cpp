// keymesh._keymesh.dask_labels_*: the passes of a label map cut into slabs of
// z-planes (generate/labels_stream.hpp's LabelSlabs, which the streamed and
// MPI label runs use), one call per slab and pass, for keymesh.dask's
// contour_labels (python/keymesh/dask.py):
//   distinct  -> the slab's distinct labels;
//   count     -> (every slab's distinct labels) the slab's voxel counts and boxes;
//   pieces    -> (every slab's labels and counts) the slab's pieces of the surfaces;
//   merge     -> (all of it, the pieces in slab order) the welded, smoothed mesh,
// equal to contour_labels on the whole volume bit for bit.
//
// A slab task holds padded rows [rows.first, rows.second) of the nz + 2 (the
// volume padded with one plane of background on either side) and receives
// the file planes its passes read: [first_plane, first_plane + planes).
// Label maps are read x-fastest (a Fortran-ordered copy of a C-ordered
// chunk), as keymesh.contour_labels reads them.
#include <cstring>
#include <limits>

#include "common.hpp"
#include "keymesh/generate/labels/labels.hpp"
#include "keymesh/generate/labels/labels_stream.hpp"
#include "keymesh/mesh/plane_source.hpp"

namespace keymesh::python {

namespace {

// The planes of a volume a numpy slab holds; the volume's header.
class SlabSource final : public PlaneSource {
 public:
  SlabSource(const py::object& slab, Id first_plane, const std::array<Id, 3>& whole, const py::object& spacing,
             const py::object& origin)
      : first_(first_plane) {
    if (!slab.is_none()) {
      held_ = true;
      view_ = view_array_volume(slab, spacing, origin, VolumeOrder::Fortran,
                                {"dask_labels", 1, "dask_labels: the slab must be a 3-D numpy array", true});
      header_ = view_.grid;
      header_.external = nullptr;
    }
    if (!spacing.is_none()) header_.spacing = triple(spacing, "spacing");
    if (!origin.is_none()) header_.origin = triple(origin, "origin");
    header_.dims = whole;
  }
  void set_type(ScalarType type) { header_.type = type; }
  const ImageGrid& header() const override { return header_; }
  void read_planes(Id first, Id count, std::byte* out) override {
    const Id held = held_ ? view_.grid.dims[2] : 0;
    if (first < first_ || first + count > first_ + held)
      throw InputError("dask_labels: planes [" + std::to_string(first) + ", " + std::to_string(first + count) +
                       ") asked of a slab holding [" + std::to_string(first_) + ", " + std::to_string(first_ + held) + ")");
    const std::size_t plane = static_cast<std::size_t>(header_.dims[0] * header_.dims[1]) * scalar_size(header_.type);
    std::memcpy(out, view_.grid.external + plane * static_cast<std::size_t>(first - first_),
                plane * static_cast<std::size_t>(count));
  }

 private:
  ArrayVolume view_;
  bool held_ = false;  // the merge's source holds no planes, only the header
  ImageGrid header_;
  Id first_ = 0;
};

// contour_labels' options, as a tuple (method, labels, background,
// per_label, smoothing_iterations, relaxation, coarsen, history).
generate::LabelOptions options_of(const py::tuple& o) {
  generate::LabelOptions opt =
      label_options(o[0].cast<std::string>(), o[1].cast<std::vector<std::int64_t>>(), o[2].cast<std::int64_t>(),
                    o[3].cast<bool>(), o[4].cast<int>(), o[5].cast<double>(), o[6].cast<bool>());
  opt.history = o.size() > 7 && o[7].cast<bool>();
  return opt;
}

using Rows = std::pair<Id, Id>;
using AllLabels = std::vector<std::vector<std::int64_t>>;
using Bytes = std::vector<std::byte>;

Bytes bytes_of(const py::bytes& b) {
  const std::string_view v(b);
  const auto* p = reinterpret_cast<const std::byte*>(v.data());
  return Bytes(p, p + v.size());
}
std::vector<Bytes> all_bytes(const std::vector<py::bytes>& list) {
  std::vector<Bytes> out;
  for (const py::bytes& b : list) out.push_back(bytes_of(b));
  return out;
}
py::bytes to_python(const Bytes& b) { return py::bytes(reinterpret_cast<const char*>(b.data()), b.size()); }

constexpr std::size_t kNoLimit = std::numeric_limits<std::size_t>::max();

std::vector<std::int64_t> distinct(const py::object& slab, Id first_plane, const std::array<Id, 3>& whole,
                                   const Rows& rows, const py::tuple& options) {
  SlabSource source(slab, first_plane, whole, py::none(), py::none());
  generate::LabelSlabs slabs(source, options_of(options), kNoLimit, rows);
  return run_released(1, [&] { return slabs.distinct_labels(); });
}

py::bytes count(const py::object& slab, Id first_plane, const std::array<Id, 3>& whole, const Rows& rows,
                const py::tuple& options, const AllLabels& labels) {
  SlabSource source(slab, first_plane, whole, py::none(), py::none());
  generate::LabelSlabs slabs(source, options_of(options), kNoLimit, rows);
  slabs.set_labels(labels);
  return to_python(run_released(1, [&] { return slabs.count_labels(); }));
}

py::bytes pieces(const py::object& slab, Id first_plane, const std::array<Id, 3>& whole, const Rows& rows,
                 const py::tuple& options, const AllLabels& labels, const std::vector<py::bytes>& counts,
                 const py::object& spacing, const py::object& origin, int threads) {
  SlabSource source(slab, first_plane, whole, spacing, origin);
  generate::LabelSlabs slabs(source, options_of(options), kNoLimit, rows);
  slabs.set_labels(labels);
  slabs.set_counts(all_bytes(counts));
  return to_python(run_released(threads, [&] {
    slabs.generate();
    return slabs.pieces_bytes();
  }));
}

py::tuple merge(const py::dtype& dtype, const std::array<Id, 3>& whole, const py::tuple& options,
                const AllLabels& labels, const std::vector<py::bytes>& counts, const std::vector<py::bytes>& slab_pieces,
                const py::object& spacing, const py::object& origin, int threads) {
  check_threads(threads);
  SlabSource source(py::none(), 0, whole, spacing, origin);
  source.set_type(label_scalar_type_of(dtype, "volume"));
  const generate::LabelOptions opt = options_of(options);
  generate::LabelSlabs slabs(source, opt, kNoLimit, {0, 0});
  slabs.set_labels(labels);
  slabs.set_counts(all_bytes(counts));
  const std::vector<Bytes> all = all_bytes(slab_pieces);
  std::vector<std::uint64_t> history_key;
  SurfaceMesh mesh = run_released(threads, [&] {
    for (const Bytes& b : all) slabs.add_pieces(b);
    return slabs.finish(opt.history ? &history_key : nullptr);
  });
  return with_history_key(mesh_to_python(std::move(mesh)), std::move(history_key), opt.history);
}

}  // namespace

void register_dask_labels(py::module_& m) {
  m.def("dask_labels_distinct", &distinct, py::arg("slab"), py::arg("first_plane"), py::arg("whole"), py::arg("rows"),
        py::arg("options"), "A slab's distinct labels. Use keymesh.dask.contour_labels.");
  m.def("dask_labels_count", &count, py::arg("slab"), py::arg("first_plane"), py::arg("whole"), py::arg("rows"),
        py::arg("options"), py::arg("labels"), "A slab's label counts, as bytes. Use keymesh.dask.contour_labels.");
  m.def("dask_labels_pieces", &pieces, py::arg("slab"), py::arg("first_plane"), py::arg("whole"), py::arg("rows"),
        py::arg("options"), py::arg("labels"), py::arg("counts"), py::arg("spacing"), py::arg("origin"),
        py::arg("threads") = 1, "A slab's pieces of the surfaces, as bytes. Use keymesh.dask.contour_labels.");
  m.def("dask_labels_merge", &merge, py::arg("dtype"), py::arg("whole"), py::arg("options"), py::arg("labels"),
        py::arg("counts"), py::arg("pieces"), py::arg("spacing"), py::arg("origin"), py::arg("threads") = 0,
        "The slabs' pieces welded, smoothed and coarsened: (points, cells, None, point_data, cell_data). "
        "Use keymesh.dask.contour_labels.");
}

}  // namespace keymesh::python
