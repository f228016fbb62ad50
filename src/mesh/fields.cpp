#include "keymesh/mesh/fields.hpp"

#include <algorithm>

#include "keymesh/parallel/for_each.hpp"

namespace keymesh {

std::vector<Field> new_point_fields(const std::vector<Field>& like, Id points) {
  std::vector<Field> out;
  out.reserve(like.size());
  for (const Field& f : like)
    out.push_back({f.name, f.components, std::vector<float>(static_cast<std::size_t>(points * f.components))});
  return out;
}

std::vector<Field> extend_point_fields(const std::vector<Field>& in, Id total) {
  std::vector<Field> out = new_point_fields(in, total);
  for (std::size_t i = 0; i < in.size(); ++i) std::copy(in[i].values.begin(), in[i].values.end(), out[i].values.begin());
  return out;
}


std::vector<Field> repeat_cell_fields(const std::vector<Field>& in, Id cells, int children) {
  std::vector<Field> out;
  out.reserve(in.size());
  for (const Field& f : in) {
    Field h{f.name, f.components, std::vector<float>(f.values.size() * static_cast<std::size_t>(children))};
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
