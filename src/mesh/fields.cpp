#include "keymesh/mesh/fields.hpp"

#include <algorithm>

#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/fresh_memory.hpp"

namespace keymesh {

namespace {

// to[0 .. from.size()) = from, the threads copying one range each.
void copy_prefix(const Array<float>& from, Array<float>& to) {
  const Id n = static_cast<Id>(from.size());
  parallel::for_each_chunk(n, parallel::chunk_count(n, Id{1} << 16),
                           [&](Id b, Id e, int) { std::copy(from.data() + b, from.data() + e, to.data() + b); });
}

}  // namespace

std::vector<Field> new_point_fields(const std::vector<Field>& like, Id points) {
  std::vector<Field> out;
  out.reserve(like.size());
  for (const Field& f : like) {
    out.push_back({f.name, f.components, {}});
    parallel::resize_fresh(out.back().values, static_cast<std::size_t>(points * f.components));
  }
  return out;
}

std::vector<Field> extend_point_fields(const std::vector<Field>& in, Id total) {
  std::vector<Field> out = new_point_fields(in, total);
  for (std::size_t i = 0; i < in.size(); ++i) copy_prefix(in[i].values, out[i].values);
  return out;
}

void extend_points(const Array<float>& in, Id total, Array<float>& out) {
  parallel::resize_fresh(out, static_cast<std::size_t>(3 * total));
  copy_prefix(in, out);
}


std::vector<Field> repeat_cell_fields(const std::vector<Field>& in, Id cells, int children) {
  std::vector<Field> out;
  out.reserve(in.size());
  for (const Field& f : in) {
    Field h{f.name, f.components, Array<float>(f.values.size() * static_cast<std::size_t>(children))};
    const auto k = static_cast<std::size_t>(f.components);
    parallel::for_each(cells, [&](Id c) {
      for (int t = 0; t < children; ++t)
        std::copy_n(f.values.begin() + static_cast<std::ptrdiff_t>(c * k), k,
                    h.values.begin() + static_cast<std::ptrdiff_t>((children * c + t) * k));
    });
    out.push_back(std::move(h));
  }
  return out;
}

}  // namespace keymesh
