// keymesh._keymesh.marching_cubes: the compiled half of keymesh.marching_cubes
// (python/keymesh/_skimage.py checks the arguments as scikit-image does and
// scales by spacing). See generate/classic_marching_cubes.hpp for what is
// reproduced and how.
#include <algorithm>
#include <cstring>

#include "common.hpp"
#include "keymesh/generate/classic/classic_marching_cubes.hpp"

namespace keymesh::python {

namespace {

generate::ClassicTable table_from_python(const py::handle& obj) {
  generate::ClassicTable table;
  if (obj.is_none()) return generate::classic_table();
  auto a = py::array_t<std::int8_t, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!a || a.ndim() != 2 || a.shape(0) != 256 || a.shape(1) != 16)
    throw py::value_error("marching cubes: the case table must be a (256, 16) array of edge ids");
  for (int c = 0; c < 256; ++c)
    for (int k = 0; k < 16; ++k) {
      const std::int8_t e = a.at(c, k);
      if (e < -1 || e > 11) throw py::value_error("marching cubes: case table entry out of range");
      table[c][k] = e;
    }
  return table;
}

// {name: int8 array} -> Mc33Tables (the C++ checks names, shapes, ranges).
generate::Mc33Tables mc33_from_python(const py::dict& tables) {
  generate::Mc33Tables out;
  for (const auto& [name, value] : tables) {
    auto a = py::array_t<std::int8_t, py::array::c_style | py::array::forcecast>::ensure(value);
    if (!a) throw py::value_error("marching cubes 33: every table must be an int8 array");
    generate::Mc33Array& t = out[py::cast<std::string>(name)];
    t.data.assign(a.data(), a.data() + a.size());
    for (py::ssize_t d = 0; d < a.ndim(); ++d) t.shape.push_back(static_cast<int>(a.shape(d)));
  }
  return out;
}

py::tuple marching_cubes(const py::array_t<float, py::array::c_style>& volume, double level,
                         const py::object& table_obj, int step, const py::object& mask_obj, bool descent,
                         int threads, const py::object& callback, const py::object& mc33_obj, bool history) {
  check_threads(threads);
  const PythonProgress progress(callback);
  if (volume.ndim() != 3) throw py::value_error("Input volume should be a 3D numpy array.");
  const generate::ClassicTable table = table_from_python(table_obj);
  generate::Mc33Tables mc33;
  generate::ClassicMarchingCubesOptions opt;
  if (!mc33_obj.is_none()) {
    mc33 = mc33_from_python(py::cast<py::dict>(mc33_obj));
    opt.mc33 = &mc33;
  }
  opt.level = level;
  opt.step = step;
  opt.descent = descent;
  opt.history = history;
  py::array_t<std::uint8_t, py::array::c_style> mask;
  if (!mask_obj.is_none()) {
    mask = checked_array<std::uint8_t>(mask_obj, "mask");
    if (!mask || mask.ndim() != 3 || mask.shape(0) != volume.shape(0) || mask.shape(1) != volume.shape(1) ||
        mask.shape(2) != volume.shape(2))
      throw py::value_error("volume and mask must have the same shape.");
    opt.mask = mask.data();
  }
  const std::array<Id, 3> shape{volume.shape(0), volume.shape(1), volume.shape(2)};
  generate::ClassicMarchingCubes r = run_released(
      threads, progress, [&] { return generate::classic_marching_cubes(volume.data(), shape, table, opt); });
  const auto v = static_cast<py::ssize_t>(r.values.size());
  const auto f = static_cast<py::ssize_t>(r.faces.size() / 3);
  py::tuple out = py::make_tuple(adopt(std::move(r.vertices), {v, 3}), adopt(std::move(r.faces), {f, 3}),
                                 adopt(std::move(r.normals), {v, 3}), adopt(std::move(r.values), {v}));
  if (!history) return out;
  return py::make_tuple(out[0], out[1], out[2], out[3], adopt(std::move(r.history_key), {v}),
                        adopt(std::move(r.history_t), {v}));
}

// scikit-image's remove_degenerate_faces, rule for rule: a face with two
// equal corners is dropped and the two points' map entries both take the
// lower of them (one level, in face order); points whose entry moved are
// removed, the rest renumbered in order, and the kept faces rewritten
// through both maps. Faces come back int64, as numpy's cumsum gives them.
py::tuple remove_degenerate_faces(const py::array_t<float, py::array::c_style | py::array::forcecast>& vertices,
                                  const py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>& faces,
                                  const py::list& arrays) {
  if (vertices.ndim() != 2 || vertices.shape(1) != 3 || faces.ndim() != 2 || faces.shape(1) != 3)
    throw py::value_error("remove_degenerate_faces: vertices and faces must be (n, 3)");
  const py::ssize_t nv = vertices.shape(0), nf = faces.shape(0);
  const float* v = vertices.data();
  const std::int64_t* f = faces.data();
  for (py::ssize_t i = 0; i < 3 * nf; ++i)
    if (f[i] < 0 || f[i] >= nv) throw py::value_error("remove_degenerate_faces: face index out of range");
  std::vector<std::int64_t> map1(static_cast<std::size_t>(nv));
  std::vector<char> face_ok(static_cast<std::size_t>(nf), 1);
  std::vector<char> point_ok(static_cast<std::size_t>(nv));
  std::vector<std::int64_t> map2(static_cast<std::size_t>(nv));
  std::vector<std::int64_t> kept_faces;
  {
    py::gil_scoped_release release;
    for (py::ssize_t i = 0; i < nv; ++i) map1[i] = i;
    auto same = [&](std::int64_t a, std::int64_t b) {
      return v[3 * a] == v[3 * b] && v[3 * a + 1] == v[3 * b + 1] && v[3 * a + 2] == v[3 * b + 2];
    };
    for (py::ssize_t j = 0; j < nf; ++j) {
      const std::int64_t c[3] = {f[3 * j], f[3 * j + 1], f[3 * j + 2]};
      const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
      for (const auto& p : pairs)
        if (same(c[p[0]], c[p[1]])) {
          map1[c[p[0]]] = map1[c[p[1]]] = std::min(map1[c[p[0]]], map1[c[p[1]]]);
          face_ok[j] = 0;
        }
    }
    std::int64_t next = 0;
    for (py::ssize_t i = 0; i < nv; ++i) {
      point_ok[i] = map1[i] == i;
      next += point_ok[i];
      map2[i] = next - 1;
    }
    for (py::ssize_t j = 0; j < nf; ++j)
      if (face_ok[j])
        for (int k = 0; k < 3; ++k) kept_faces.push_back(map2[map1[f[3 * j + k]]]);
  }
  py::array_t<bool> selection(nv);
  std::copy(point_ok.begin(), point_ok.end(), selection.mutable_data());
  py::list out;
  out.append(py::reinterpret_borrow<py::object>(vertices)[selection]);
  const auto kept = static_cast<py::ssize_t>(kept_faces.size() / 3);
  out.append(adopt(std::move(kept_faces), {kept, 3}));
  for (const auto& a : arrays) out.append(a[selection]);
  return py::tuple(out);
}

py::array classic_table_array() {
  const generate::ClassicTable t = generate::classic_table();
  std::vector<std::int8_t> flat(256 * 16);
  for (int c = 0; c < 256; ++c) std::memcpy(&flat[16 * c], t[c].data(), 16);
  return adopt(std::move(flat), {256, 16});
}

}  // namespace

void register_marching_cubes(py::module_& m) {
  m.def("marching_cubes", &marching_cubes, py::arg("volume"), py::arg("level"), py::arg("table") = py::none(),
        py::arg("step") = 1, py::arg("mask") = py::none(), py::arg("descent") = true, py::arg("threads") = 0,
        py::arg("progress") = py::none(), py::arg("mc33") = py::none(), py::arg("history") = false,
        "scikit-image-compatible marching cubes on a C-ordered float32 volume; returns (verts, faces, "
        "normals, values) at unit spacing, and (history_key, history_t) with history; mc33: {name: int8 array} of Lewiner's tables for "
        "method='lewiner'. Use keymesh.marching_cubes.");
  m.def("remove_degenerate_faces", &remove_degenerate_faces, py::arg("vertices"), py::arg("faces"),
        py::arg("arrays"), "scikit-image's remove_degenerate_faces: (vertices, faces int64, *arrays).");
  m.def("classic_table", &classic_table_array,
        "keymesh's marching cubes case table in the classic (Lorensen/Bourke) edge numbering, (256, 16) int8.");
}

}  // namespace keymesh::python
