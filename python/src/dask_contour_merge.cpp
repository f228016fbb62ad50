// keymesh._keymesh.dask_contour_merge: the Dask chunks' pieces
// (dask_contour_block.cpp) welded into the contour of the whole grid, the
// mesh keymesh.contour gives for the whole array, bit for bit.
//
//  - points: one KEY-REDUCE over every piece's global edge keys. A point on
//    a face two chunks share comes from both, computed from the same two
//    samples with the same whole-grid indices: the same bits; the first of
//    its group stands for it. Groups come in increasing key, the order the
//    whole grid's contour numbers its points in.
//  - triangles: a second KEY-REDUCE, over the triangles' ranks (isovalue,
//    voxel); its pair order is the whole contour's triangle order, since
//    every voxel is one chunk's and a group keeps its pairs in increasing
//    index (a voxel's triangles in their table order).
//  - averaged normals: summed over the merged mesh in the blocks of voxel
//    layers the whole contour sums them in (generate/layer_blocks.hpp, as
//    the streamed and MPI contours do); coarsening: the merged fine mesh
//    coarsened by its points' nearest grid points at once, as the in-memory
//    --coarsen does (the slab-by-slab streamed one gives the same bytes).
//  - a C-ordered volume was contoured with its axes reversed: mirrored back
//    last, as keymesh.contour does.
#include <limits>

#include "common.hpp"
#include "keymesh/generate/coarsen/coarsen.hpp"
#include "keymesh/generate/contour/layer_blocks.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/mesh/normals.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"

namespace keymesh::python {

namespace {

template <class T>
using CArray = py::array_t<T, py::array::c_style | py::array::forcecast>;

// Every piece's arrays one after the other; cells index the whole list.
struct Concatenated {
  std::vector<std::uint64_t> keys, nearest, rank;
  std::vector<float> points;
  std::vector<PointIndex> cells;
  std::vector<Field> fields;
  bool reversed = false;
};

template <class T, class V>
void append(V& to, const py::handle& array) {
  const auto a = CArray<T>::ensure(array);
  if (!a) throw py::type_error("dask_contour_merge: a piece's array has the wrong type");
  to.insert(to.end(), a.data(), a.data() + a.size());
}

Concatenated concatenate(const py::list& pieces, bool coarse) {
  Concatenated all;
  for (const py::handle piece : pieces) {
    const auto t = piece.cast<py::tuple>();
    if (t.size() != 7) throw py::value_error("dask_contour_merge: a piece is not dask_contour_block's 7-tuple");
    const std::size_t base = all.keys.size(), first_cell = all.cells.size();
    append<std::uint64_t>(all.keys, t[0]);
    if (coarse) append<std::uint64_t>(all.nearest, t[1]);
    append<float>(all.points, t[2]);
    append<PointIndex>(all.cells, t[3]);
    append<std::uint64_t>(all.rank, t[4]);
    all.reversed = t[6].cast<bool>();
    if (all.keys.size() > std::numeric_limits<PointIndex>::max())
      throw LimitError("keymesh.dask: more than 2^32 - 1 points before merging");
    for (std::size_t c = first_cell; c < all.cells.size(); ++c) all.cells[c] += static_cast<PointIndex>(base);
    const auto fields = t[5].cast<py::list>();
    if (all.fields.empty() && base == 0)
      for (const py::handle f : fields) {
        const auto nf = f.cast<py::tuple>();
        const auto values = CArray<float>::ensure(nf[1]);
        all.fields.push_back(Field{nf[0].cast<std::string>(), values.ndim() > 1 ? static_cast<int>(values.shape(1)) : 1, {}});
      }
    if (fields.size() != all.fields.size()) throw py::value_error("dask_contour_merge: pieces carry different fields");
    for (std::size_t i = 0; i < all.fields.size(); ++i)
      append<float>(all.fields[i].values, fields[i].cast<py::tuple>()[1]);
  }
  return all;
}

// Where the whole grid's keys end: its dims in the library's axes.
struct WholeGrid {
  std::uint64_t nx = 0, ny = 0, nz = 0, isovalues = 1;
  std::uint64_t points() const { return nx * ny * nz; }
  std::uint64_t voxels() const { return (nx - 1) * (ny - 1) * (nz - 1); }
};

// KEY-REDUCE's partition of keys below key_range: the dense plan (a bitmap
// of the range, no sort) where the bitmap takes no more than a word per
// key, else the sort plan; both give the same groups.
keyreduce::Groups<std::uint64_t> partition(const std::vector<std::uint64_t>& keys, std::uint64_t key_range) {
  const Id n = static_cast<Id>(keys.size());
  if (key_range / 64 <= keys.size()) return keyreduce::partition_dense(keys.data(), n, key_range, keyreduce::Order::Build);
  return keyreduce::partition_sort(keys.data(), n, parallel::bits_needed<std::uint64_t>(key_range - 1),
                                   keyreduce::Order::Build);
}

SurfaceMesh weld(const Concatenated& all, const WholeGrid& w, std::vector<std::uint64_t>& point_keys,
                 std::vector<std::uint64_t>& nearest) {
  const Id m = static_cast<Id>(all.rank.size());
  const auto g = partition(all.keys, 3 * w.points() * w.isovalues);
  const auto tri = partition(all.rank, w.voxels() * w.isovalues);
  SurfaceMesh mesh;
  const Id unique = g.num_groups();
  mesh.points.resize(static_cast<std::size_t>(3 * unique));
  for (const Field& f : all.fields)
    mesh.point_fields.push_back(Field{f.name, f.components, Array<float>(static_cast<std::size_t>(unique * f.components))});
  point_keys.assign(g.unique_keys.begin(), g.unique_keys.end());
  nearest.resize(all.nearest.empty() ? 0 : static_cast<std::size_t>(unique));
  parallel::for_each(unique, [&](Id p) {
    const Id first = g.order[g.offsets[p]];
    if (!nearest.empty()) nearest[p] = all.nearest[first];
    std::copy_n(all.points.begin() + 3 * first, 3, mesh.points.begin() + 3 * p);
    for (std::size_t i = 0; i < all.fields.size(); ++i) {
      const int c = all.fields[i].components;
      std::copy_n(all.fields[i].values.begin() + c * first, c, mesh.point_fields[i].values.begin() + c * p);
    }
  });
  mesh.connectivity.resize(static_cast<std::size_t>(3 * m));
  parallel::for_each(m, [&](Id t) {
    const std::uint32_t from = tri.order[t];
    for (int c = 0; c < 3; ++c) mesh.connectivity[3 * t + c] = g.index_map[all.cells[3 * from + c]];
  });
  return mesh;
}

py::tuple contour_merge(const py::list& pieces, const std::array<Id, 3>& whole, Id isovalues, bool average,
                        bool coarsen, bool history, int threads) {
  check_threads(threads);
  const Concatenated all = concatenate(pieces, coarsen);
  // whole: the array's dims; the pieces' keys are the library's (reversed for a C-ordered array).
  const int x = all.reversed ? 2 : 0, z = all.reversed ? 0 : 2;
  const WholeGrid w{static_cast<std::uint64_t>(whole[x]), static_cast<std::uint64_t>(whole[1]),
                    static_cast<std::uint64_t>(whole[z]), static_cast<std::uint64_t>(isovalues)};
  std::vector<std::uint64_t> history_key;
  SurfaceMesh mesh = run_released(threads, [&] {
    std::vector<std::uint64_t> point_keys, nearest;
    SurfaceMesh m = weld(all, w, point_keys, nearest);
    if (history) {  // a point's history_key is its whole-grid edge key
      history_key = point_keys;
      if (all.reversed)
        keys_in_array_frame(history_key, {static_cast<Id>(w.nx), static_cast<Id>(w.ny), static_cast<Id>(w.nz)});
    }
    if (average && !coarsen)
      m.point_fields.push_back(generate::blocked_average_normals(
          m, generate::layer_blocks(m, point_keys, generate::LayerGrid{w.nx * w.ny, static_cast<Id>(w.nz) - 1, isovalues})));
    if (coarsen) {
      m = generate::coarsen(m, nearest, w.points() * w.isovalues);
      if (average) average_normals(m);
    }
    if (all.reversed) mirror_axes(m);
    return m;
  });
  py::tuple parts = mesh_to_python(std::move(mesh));
  if (history) {
    const auto n = static_cast<py::ssize_t>(history_key.size());
    parts[3].cast<py::dict>()["history_key"] = adopt(std::move(history_key), {n});
  }
  return parts;
}

}  // namespace

void register_dask_contour_merge(py::module_& m) {
  m.def("dask_contour_merge", &contour_merge, py::arg("pieces"), py::arg("whole"), py::arg("isovalues"),
        py::arg("average") = false, py::arg("coarsen") = false, py::arg("history") = false, py::arg("threads") = 0,
        "The pieces of dask_contour_block welded into the whole grid's contour: (points, cells, None, "
        "point_data, cell_data). Use keymesh.dask.contour.");
}

}  // namespace keymesh::python
