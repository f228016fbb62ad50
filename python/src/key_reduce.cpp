// keymesh.key_reduce: the library's KEY-REDUCE (partition by key with the
// sort plan, then a reduction per group) over numpy keys and values.
#include <bit>
#include <cmath>
#include <cstdint>

#include "common.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/keyreduce/pair_count.hpp"
#include "keymesh/keyreduce/reduce.hpp"

namespace keymesh::python {

namespace {

enum class Op { Mean, Sum, Min, Max };

Op parse_op(const std::string& s) {
  if (s == "mean") return Op::Mean;
  if (s == "sum") return Op::Sum;
  if (s == "min") return Op::Min;
  if (s == "max") return Op::Max;
  throw py::value_error("op must be 'mean', 'sum', 'min' or 'max', got '" + s + "'");
}

// Reduces column `col` of the (n, cols) values into column `col` of the
// (groups, cols) output. Sums and means accumulate in double; min and max
// propagate NaN like numpy.minimum / numpy.maximum.
template <class K, class V>
void reduce_column(const keyreduce::Groups<K>& groups, const V* values, Id cols, Id col, Op op, V* out) {
  std::vector<V> column(static_cast<std::size_t>(groups.num_groups()));
  auto value = [=](Id i) { return values[i * cols + col]; };
  auto widen = [=](Id i) { return static_cast<double>(values[i * cols + col]); };
  auto add = [](double a, double b) { return a + b; };
  switch (op) {
    case Op::Sum:
      keyreduce::reduce(groups, widen, add, [](double s, Id) { return static_cast<V>(s); }, column.data());
      break;
    case Op::Mean:
      keyreduce::reduce(
          groups, widen, add, [](double s, Id c) { return static_cast<V>(s / static_cast<double>(c)); }, column.data());
      break;
    case Op::Min:
      keyreduce::reduce(
          groups, value, [](V a, V b) { return (std::isnan(a) || a <= b) ? a : b; }, [](V v, Id) { return v; },
          column.data());
      break;
    case Op::Max:
      keyreduce::reduce(
          groups, value, [](V a, V b) { return (std::isnan(a) || a >= b) ? a : b; }, [](V v, Id) { return v; },
          column.data());
      break;
  }
  for (std::size_t g = 0; g < column.size(); ++g) out[g * static_cast<std::size_t>(cols) + static_cast<std::size_t>(col)] = column[g];
}

template <class K, class KeyView, class V>
py::tuple key_reduce_typed(const K* keys, Id n, const py::array& values_in, Op op) {
  auto values = checked_array<V>(values_in, "values");
  const Id cols = values.ndim() == 2 ? static_cast<Id>(values.shape(1)) : 1;
  keyreduce::Groups<K> groups;
  std::vector<V> reduced;
  std::vector<std::int64_t> counts;
  {
    py::gil_scoped_release release;
    K max_key = 0;
    for (Id i = 0; i < n; ++i) max_key = std::max(max_key, keys[i]);
    groups = keyreduce::partition_sort(keys, n, std::max(1, static_cast<int>(std::bit_width(max_key))));
    const Id g_count = groups.num_groups();
    reduced.resize(static_cast<std::size_t>(g_count * cols));
    for (Id c = 0; c < cols; ++c) reduce_column(groups, values.data(), cols, c, op, reduced.data());
    counts.resize(static_cast<std::size_t>(g_count));
    for (Id g = 0; g < g_count; ++g) counts[static_cast<std::size_t>(g)] = groups.count(g);
  }
  const py::ssize_t g_count = groups.num_groups();
  std::vector<py::ssize_t> shape{g_count};
  if (values.ndim() == 2) shape.push_back(cols);
  return py::make_tuple(adopt<KeyView>(std::move(groups.unique_keys), {g_count}), adopt(std::move(reduced), shape),
                        adopt(std::move(groups.index_map), {static_cast<py::ssize_t>(n)}),
                        adopt(std::move(counts), {g_count}));
}

template <class K, class KeyView>
py::tuple key_reduce_keys(const py::array& keys_in, const py::array& values, Op op) {
  auto keys = checked_array<K>(keys_in, "keys");
  const Id n = static_cast<Id>(keys.size());
  if (values.dtype().kind() == 'f' && values.dtype().itemsize() == 4)
    return key_reduce_typed<K, KeyView, float>(keys.data(), n, values, op);
  return key_reduce_typed<K, KeyView, double>(keys.data(), n, values, op);
}

py::tuple key_reduce(const py::object& keys_obj, const py::object& values_obj, const std::string& op_name,
                     int threads) {
  check_threads(threads);
  const Op op = parse_op(op_name);
  py::array keys = py::array::ensure(keys_obj);
  py::array values = py::array::ensure(values_obj);
  if (!keys || !values) throw py::type_error("key_reduce: keys and values must be numpy arrays");
  if (keys.ndim() != 1) throw py::value_error("keys must be 1-D, got ndim=" + std::to_string(keys.ndim()));
  if (values.ndim() != 1 && values.ndim() != 2)
    throw py::value_error("values must be 1-D or 2-D (one row per key), got ndim=" + std::to_string(values.ndim()));
  if (values.shape(0) != keys.shape(0))
    throw py::value_error("values has " + std::to_string(values.shape(0)) + " rows but keys has " +
                          std::to_string(keys.shape(0)) + " entries");
  const py::dtype vt = values.dtype();
  if (vt.kind() != 'f' || (vt.itemsize() != 4 && vt.itemsize() != 8))
    throw py::type_error("values must be float32 or float64, got dtype " + dtype_name(vt));
  const py::dtype kt = keys.dtype();
  // Before any copy (the byte order's, the layout's): the index map's limit.
  keyreduce::check_pair_count(static_cast<Id>(keys.shape(0)));
  ThreadScope scope(threads);
  if (kt.kind() == 'u' && kt.itemsize() == 4) return key_reduce_keys<std::uint32_t, std::uint32_t>(keys, values, op);
  if (kt.kind() == 'u' && kt.itemsize() == 8) return key_reduce_keys<std::uint64_t, std::uint64_t>(keys, values, op);
  if (kt.kind() == 'i' && kt.itemsize() == 8) {
    auto signed_keys = checked_array<std::int64_t>(keys, "keys");
    const std::int64_t* k = signed_keys.data();
    for (py::ssize_t i = 0; i < signed_keys.size(); ++i)
      if (k[i] < 0) throw py::value_error("keys must be non-negative, keys[" + std::to_string(i) + "] = " + std::to_string(k[i]));
    // Non-negative int64 keys are the same bits as uint64.
    return key_reduce_keys<std::uint64_t, std::int64_t>(signed_keys.attr("view")("uint64"), values, op);
  }
  throw py::type_error("keys must be uint32, uint64 or int64, got dtype " + dtype_name(kt));
}

}  // namespace

void register_key_reduce(py::module_& m) {
  m.def("key_reduce", &key_reduce, py::arg("keys"), py::arg("values"), py::arg("op") = "mean", py::arg("threads") = 0,
        "KEY-REDUCE; returns (unique_keys, reduced, index_map, counts). Use keymesh.key_reduce.");
}

}  // namespace keymesh::python
