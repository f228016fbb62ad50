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

void mean_position(const float* P, const std::uint64_t* ids, int n, float* xyz) {
  for (int x = 0; x < 3; ++x) {
    double s = 0;
    for (int j = 0; j < n; ++j) s += P[3 * ids[j] + x];
    xyz[x] = static_cast<float>(s / n);
  }
}

void average_point_fields(const std::vector<Field>& in, std::vector<Field>& out, Id point, const std::uint64_t* ids,
                          int n) {
  for (std::size_t i = 0; i < in.size(); ++i) {
    const int k = in[i].components;
    for (int c = 0; c < k; ++c) {
      double s = 0;
      for (int j = 0; j < n; ++j) s += in[i].values[ids[j] * k + c];
      out[i].values[point * k + c] = static_cast<float>(s / n);
    }
  }
}

void midpoint_tuple(const Field& f, Field& f_out, Id point, std::uint64_t a, std::uint64_t b) {
  const int k = f.components;
  for (int c = 0; c < k; ++c) f_out.values[point * k + c] = 0.5f * (f.values[a * k + c] + f.values[b * k + c]);
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
