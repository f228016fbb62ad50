// keymesh._keymesh.dask_contour_block: one Dask chunk's contour, with the
// whole grid's keys (python/keymesh/dask.py; the merge: dask_contour_merge.cpp).
//
// The task receives a box of the whole grid's samples: the chunk's own
// samples, one plane more on its high sides (the cubes between the chunk and
// its neighbour are the chunk's: every voxel belongs to exactly one chunk)
// and, for gradient normals or curvature, one ghost plane on every side that
// has a neighbour (central differences across the border). The box is
// contoured as a grid of its own with positions computed from the whole
// grid's indices (ContourOptions::position_offset: the same bits as the
// whole grid's contour), then
//  - each point's key, 3 * point id + axis of the box, is renumbered as the
//    whole grid's (3 * global point id + axis, + isovalue * 3N), and so is
//    its coarse key (its edge's end nearest to it, + isovalue * N);
//  - each triangle gets its voxel: for every axis the least grid coordinate
//    of its corners' edges (a marching cubes triangle never has its three
//    edges on one face of its cube: tests/generate/
//    marching_cubes_table_test.cpp checks the table), and the triangles of
//    voxels the chunk does not own (ghost voxels) are dropped with the
//    points only they use;
//  - each triangle's rank in the whole contour's order: isovalue, then voxel
//    (x fastest), the order marching cubes writes them in; a voxel's
//    triangles keep their table order.
// Points stay in the box's key order, which is the whole grid's key order
// restricted to the box: the merge needs no more.
#include <algorithm>
#include <cmath>

#include "common.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/option_names.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh::python {

namespace {

using Triple = std::array<Id, 3>;

// Where the box lies in the whole grid, in the library's axes (x fastest).
struct BoxFrame {
  Triple first{}, box{}, whole{}, own_lo{}, own_hi{};  // own_*: the chunk's voxels, whole-grid indices
  Id isovalues = 1;

  std::uint64_t whole_points() const { return static_cast<std::uint64_t>(whole[0] * whole[1] * whole[2]); }
  std::uint64_t box_points() const { return static_cast<std::uint64_t>(box[0] * box[1] * box[2]); }
  // The whole grid's id of the box's grid point p.
  std::uint64_t global_point(std::uint64_t p, Triple* ijk = nullptr) const {
    const auto bx = static_cast<std::uint64_t>(box[0]), bxy = bx * static_cast<std::uint64_t>(box[1]);
    const Id i = static_cast<Id>(p % bx), j = static_cast<Id>(p % bxy / bx), k = static_cast<Id>(p / bxy);
    if (ijk) *ijk = {i, j, k};
    return static_cast<std::uint64_t>((first[0] + i) + whole[0] * ((first[1] + j) + whole[1] * (first[2] + k)));
  }
  std::uint64_t global_edge_key(std::uint64_t key) const {
    const std::uint64_t per_iso = 3 * box_points(), iso = key / per_iso, edge = key % per_iso;
    return iso * 3 * whole_points() + 3 * global_point(edge / 3) + edge % 3;
  }
  std::uint64_t global_point_key(std::uint64_t key) const {
    const std::uint64_t iso = key / box_points();
    return iso * whole_points() + global_point(key % box_points());
  }
};

// The triangle's voxel in the whole grid and its isovalue, from its corners'
// box keys; whether the chunk owns it, and its rank key (isovalue, voxel).
struct TriangleVoxel {
  bool owned = false;
  std::uint64_t rank = 0;
};

TriangleVoxel triangle_voxel(const BoxFrame& f, const std::uint64_t* corner_keys) {
  const std::uint64_t per_iso = 3 * f.box_points();
  Triple voxel{f.box[0], f.box[1], f.box[2]};
  for (int c = 0; c < 3; ++c) {
    Triple ijk;
    f.global_point(corner_keys[c] % per_iso / 3, &ijk);
    for (int a = 0; a < 3; ++a) voxel[a] = std::min(voxel[a], ijk[a]);
  }
  TriangleVoxel t;
  t.owned = true;
  for (int a = 0; a < 3; ++a) {
    voxel[a] += f.first[a];
    t.owned = t.owned && voxel[a] >= f.own_lo[a] && voxel[a] < f.own_hi[a];
  }
  const auto vx = static_cast<std::uint64_t>(f.whole[0] - 1), vy = static_cast<std::uint64_t>(f.whole[1] - 1);
  const auto vz = static_cast<std::uint64_t>(f.whole[2] - 1);
  const std::uint64_t iso = corner_keys[0] / per_iso;
  t.rank = iso * vx * vy * vz + static_cast<std::uint64_t>(voxel[0]) +
           vx * (static_cast<std::uint64_t>(voxel[1]) + vy * static_cast<std::uint64_t>(voxel[2]));
  return t;
}

// The chunk's piece: its owned triangles and the points they use, renumbered.
struct BlockPiece {
  std::vector<std::uint64_t> keys, nearest, rank;
  std::vector<float> points;
  std::vector<PointIndex> cells;
  std::vector<Field> fields;
};

// Which triangles and points the piece keeps (all of them unless the box has
// ghost planes): the kept ones' indices, in order, and each point's new id.
struct Kept {
  std::vector<Id> triangles, points;
  std::vector<PointIndex> new_id;
};

Kept kept_elements(const SurfaceMesh& mesh, const std::vector<TriangleVoxel>& voxel) {
  const Id n = mesh.num_points(), m = mesh.num_cells();
  Kept k;
  k.new_id.assign(static_cast<std::size_t>(n), 0);
  for (Id t = 0; t < m; ++t)
    if (voxel[t].owned) {
      k.triangles.push_back(t);
      for (int c = 0; c < 3; ++c) k.new_id[mesh.connectivity[3 * t + c]] = 1;
    }
  for (Id p = 0; p < n; ++p)
    if (k.new_id[p]) {
      k.new_id[p] = static_cast<PointIndex>(k.points.size());
      k.points.push_back(p);
    }
  return k;
}

BlockPiece owned_piece(const SurfaceMesh& mesh, const std::vector<std::uint64_t>& keys,
                       const std::vector<std::uint64_t>& nearest, const BoxFrame& f) {
  std::vector<TriangleVoxel> voxel(static_cast<std::size_t>(mesh.num_cells()));
  parallel::for_each(mesh.num_cells(), [&](Id t) {
    const PointIndex* c = mesh.connectivity.data() + 3 * t;
    const std::uint64_t corner_keys[3] = {keys[c[0]], keys[c[1]], keys[c[2]]};
    voxel[t] = triangle_voxel(f, corner_keys);
  });
  const Kept k = kept_elements(mesh, voxel);
  const Id n = static_cast<Id>(k.points.size()), m = static_cast<Id>(k.triangles.size());
  BlockPiece out;
  out.rank.resize(static_cast<std::size_t>(m));
  out.cells.resize(static_cast<std::size_t>(3 * m));
  parallel::for_each(m, [&](Id i) {
    const Id t = k.triangles[i];
    out.rank[i] = voxel[t].rank;
    for (int c = 0; c < 3; ++c) out.cells[3 * i + c] = k.new_id[mesh.connectivity[3 * t + c]];
  });
  out.keys.resize(static_cast<std::size_t>(n));
  out.nearest.resize(nearest.empty() ? 0 : static_cast<std::size_t>(n));
  out.points.resize(static_cast<std::size_t>(3 * n));
  for (const Field& fd : mesh.point_fields)
    out.fields.push_back(Field{fd.name, fd.components, Array<float>(static_cast<std::size_t>(n * fd.components))});
  parallel::for_each(n, [&](Id i) {
    const Id p = k.points[i];
    out.keys[i] = f.global_edge_key(keys[p]);
    if (!nearest.empty()) out.nearest[i] = f.global_point_key(nearest[p]);
    std::copy_n(mesh.points.begin() + 3 * p, 3, out.points.begin() + 3 * i);
    for (std::size_t j = 0; j < out.fields.size(); ++j) {
      const int c = out.fields[j].components;
      std::copy_n(mesh.point_fields[j].values.begin() + c * p, c, out.fields[j].values.begin() + c * i);
    }
  });
  return out;
}

Triple to_library(const Triple& t, bool reversed) { return reversed ? Triple{t[2], t[1], t[0]} : t; }

py::tuple contour_block(const py::object& block, const std::vector<double>& isovalues, const py::object& spacing,
                        const py::object& origin, const Triple& first, const Triple& whole, const Triple& own_lo,
                        const Triple& own_hi, const std::string& normals, bool curvature, bool scalars,
                        bool coarse_keys, bool history, int threads) {
  check_threads(threads);
  const ArrayVolume view = view_array_volume(block, spacing, origin, VolumeOrder::CAsReversedAxes,
                                             {"dask_contour_block", 1, "dask_contour_block: the chunk must be a 3-D numpy array"});
  BoxFrame f;
  f.first = to_library(first, view.reversed);
  f.whole = to_library(whole, view.reversed);
  f.own_lo = to_library(own_lo, view.reversed);
  f.own_hi = to_library(own_hi, view.reversed);
  f.box = {view.grid.dims[0], view.grid.dims[1], view.grid.dims[2]};
  f.isovalues = static_cast<Id>(isovalues.size());
  generate::ContourOptions opt;
  opt.isovalues = isovalues;
  opt.normals = generate::parse_option<generate::ContourNormals>(normals);
  if (opt.normals == generate::ContourNormals::Average)
    throw py::value_error("dask_contour_block: averaged normals are summed by the merge, not per chunk");
  opt.curvature = curvature;
  opt.scalars = scalars;
  opt.history = history;  // history_t: positions are the whole grid's, so is t
  opt.reversed_axes = view.reversed;
  for (int a = 0; a < 3; ++a) opt.position_offset[a] = f.first[a];
  BlockPiece piece = run_released(threads, [&] {
    std::vector<std::uint64_t> keys, nearest;
    const SurfaceMesh mesh = generate::contour(view.grid, opt, nullptr, &keys, coarse_keys ? &nearest : nullptr);
    return owned_piece(mesh, keys, nearest, f);
  });
  const auto n = static_cast<py::ssize_t>(piece.keys.size()), m = static_cast<py::ssize_t>(piece.rank.size());
  py::list fields;
  for (Field& fd : piece.fields) {
    std::vector<py::ssize_t> shape{n};
    if (fd.components > 1) shape.push_back(fd.components);
    fields.append(py::make_tuple(fd.name, adopt(std::move(fd.values), shape)));
  }
  const bool with_nearest = coarse_keys;
  return py::make_tuple(adopt(std::move(piece.keys), {n}), with_nearest ? py::object(adopt(std::move(piece.nearest), {n})) : py::none(),
                        adopt(std::move(piece.points), {n, 3}), adopt(std::move(piece.cells), {m, 3}),
                        adopt(std::move(piece.rank), {m}), fields, view.reversed);
}

}  // namespace

void register_dask_contour_block(py::module_& m) {
  m.def("dask_contour_block", &contour_block, py::arg("block"), py::arg("isovalues"), py::arg("spacing"),
        py::arg("origin"), py::arg("first"), py::arg("whole"), py::arg("own_lo"), py::arg("own_hi"),
        py::arg("normals") = "none", py::arg("curvature") = false, py::arg("scalars") = true,
        py::arg("coarse_keys") = false, py::arg("history") = false, py::arg("threads") = 1,
        "One Dask chunk's contour with the whole grid's keys: (keys, coarse keys or None, points, cells, "
        "triangle ranks, [(field name, values)], reversed axes). Use keymesh.dask.contour.");
}

}  // namespace keymesh::python
