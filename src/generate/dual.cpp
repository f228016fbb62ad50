#include "keymesh/generate/dual.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "keymesh/analyze/incidence.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/core/progress.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/scan.hpp"

namespace keymesh::generate {

namespace {

// Around point p, each incident corner of cell c gives the link a -> b
// between the corner's next and previous points. The fans of p are the
// chains of links; `visit(fan_corners, open)` is called for each fan with its
// corners in walking order. Corner lists are short (the valence), so the
// quadratic search is cheap and needs no allocation beyond the scratch arrays.
template <class Visit>
void fans_of(const SurfaceMesh& m, const analyze::PointCells& pc, Id p, std::vector<std::uint32_t>& fan,
             std::vector<std::uint8_t>& used, Visit&& visit) {
  const Id b = pc.offsets[p], k = pc.count(p);
  auto next_of = [&](std::uint32_t corner) {
    const std::uint32_t c = pc.cell_of_corner[corner];
    return m.connectivity[corner + 1 < m.cell_end(c) ? corner + 1 : m.cell_begin(c)];
  };
  auto prev_of = [&](std::uint32_t corner) {
    const std::uint32_t c = pc.cell_of_corner[corner];
    return m.connectivity[corner > m.cell_begin(c) ? corner - 1 : m.cell_end(c) - 1];
  };
  used.assign(static_cast<std::size_t>(k), 0);
  for (Id done = 0; done < k;) {
    // Start a fan where no unused link leads in (an open fan's first cell);
    // otherwise at the first unused corner (a closed fan).
    Id start = -1;
    for (Id i = 0; i < k && start < 0; ++i) {
      if (used[i]) continue;
      const PointIndex a = next_of(pc.corners[b + i]);
      bool led_into = false;
      for (Id j = 0; j < k && !led_into; ++j) led_into = !used[j] && j != i && prev_of(pc.corners[b + j]) == a;
      if (!led_into) start = i;
    }
    const bool open = start >= 0;
    if (!open)
      for (Id i = 0; i < k && start < 0; ++i)
        if (!used[i]) start = i;
    fan.clear();
    for (Id cur = start; cur >= 0;) {
      used[cur] = 1;
      ++done;
      fan.push_back(pc.corners[b + cur]);
      const PointIndex want = prev_of(pc.corners[b + cur]);
      Id nxt = -1;
      for (Id j = 0; j < k && nxt < 0; ++j)
        if (!used[j] && next_of(pc.corners[b + j]) == want) nxt = j;
      cur = nxt;
    }
    visit(fan, open);
  }
}

// Pass 1 of the dual: per point, the polygons and corners it contributes,
// whether it needs its own dual point (an open fan), and the fan counts;
// then their prefix sums (poly_count, corner_count and self become first
// indices).
struct FanCounts {
  std::vector<Id> poly_count, corner_count, self, fans, open_fans, skipped;
  Id polys = 0, corners = 0, extra = 0;
};

// A fan becomes a polygon when it has three corners at least, counting the
// point itself for an open fan (which also needs two cells).
bool fan_is_polygon(const std::vector<std::uint32_t>& f, bool open) {
  const Id size = static_cast<Id>(f.size()) + (open ? 1 : 0);
  return size >= 3 && !(open && f.size() < 2);
}

FanCounts count_fans(const SurfaceMesh& m, const analyze::PointCells& pc, int chunks) {
  const Id V = m.num_points();
  FanCounts fc;
  for (auto* v : {&fc.poly_count, &fc.corner_count, &fc.self, &fc.fans, &fc.open_fans, &fc.skipped})
    v->assign(static_cast<std::size_t>(V + 1), 0);
  parallel::for_each_chunk(V, chunks, [&](Id lo, Id hi, int) {
    std::vector<std::uint32_t> fan;
    std::vector<std::uint8_t> used;
    for (Id p = lo; p < hi; ++p)
      fans_of(m, pc, p, fan, used, [&](const std::vector<std::uint32_t>& f, bool open) {
        ++fc.fans[p];
        fc.open_fans[p] += open;
        if (!fan_is_polygon(f, open)) {
          ++fc.skipped[p];
          return;
        }
        ++fc.poly_count[p];
        fc.corner_count[p] += static_cast<Id>(f.size()) + (open ? 1 : 0);
        if (open) fc.self[p] = 1;
      });
  });
  fc.polys = parallel::exclusive_scan(fc.poly_count.data(), fc.poly_count.data(), V + 1);
  fc.corners = parallel::exclusive_scan(fc.corner_count.data(), fc.corner_count.data(), V + 1);
  fc.extra = parallel::exclusive_scan(fc.self.data(), fc.self.data(), V + 1);
  return fc;
}

// The dual's points: every cell's centroid (fields averaged alike, normals
// renormalised), then a copy of every point with an open fan.
void dual_points(const SurfaceMesh& m, const FanCounts& fc, SurfaceMesh& out) {
  const Id V = m.num_points(), F = m.num_cells();
  out.points.resize(static_cast<std::size_t>(3 * (F + fc.extra)));
  for (const Field& f : m.point_fields)
    out.point_fields.push_back({f.name, f.components, std::vector<float>(static_cast<std::size_t>((F + fc.extra) * f.components))});
  parallel::for_each(F, [&](Id c) {
    const std::uint64_t b = m.cell_begin(c), e = m.cell_end(c);
    const double w = 1.0 / double(e - b);
    for (int x = 0; x < 3; ++x) {
      double s = 0;
      for (std::uint64_t k = b; k < e; ++k) s += m.points[3 * std::size_t(m.connectivity[k]) + x];
      out.points[3 * c + x] = static_cast<float>(s * w);
    }
    for (std::size_t i = 0; i < m.point_fields.size(); ++i) {
      const Field& f = m.point_fields[i];
      for (int x = 0; x < f.components; ++x) {
        double s = 0;
        for (std::uint64_t k = b; k < e; ++k) s += f.values[std::size_t(m.connectivity[k]) * f.components + x];
        out.point_fields[i].values[c * f.components + x] = static_cast<float>(s * w);
      }
    }
  });
  parallel::for_each(V, [&](Id p) {
    if (fc.self[p + 1] == fc.self[p]) return;
    const Id q = F + fc.self[p];
    for (int x = 0; x < 3; ++x) out.points[3 * q + x] = m.points[3 * p + x];
    for (std::size_t i = 0; i < m.point_fields.size(); ++i) {
      const int k = m.point_fields[i].components;
      std::copy_n(m.point_fields[i].values.begin() + p * k, k, out.point_fields[i].values.begin() + q * k);
    }
  });
  for (Field& f : out.point_fields)
    if (f.name == "Normals" && f.components == 3)
      parallel::for_each(F, [&](Id c) {
        float* v = &f.values[3 * c];
        const float l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (l > 0) v[0] /= l, v[1] /= l, v[2] /= l;
      });
}

// Pass 2: the polygons, point by point (so in input point order).
void dual_polygons(const SurfaceMesh& m, const analyze::PointCells& pc, const FanCounts& fc, int chunks,
                   SurfaceMesh& out) {
  const Id V = m.num_points(), F = m.num_cells();
  out.connectivity.resize(static_cast<std::size_t>(fc.corners));
  out.offsets.resize(static_cast<std::size_t>(fc.polys + 1));
  out.offsets[fc.polys] = static_cast<std::uint64_t>(fc.corners);
  parallel::for_each_chunk(V, chunks, [&](Id lo, Id hi, int) {
    std::vector<std::uint32_t> fan;
    std::vector<std::uint8_t> used;
    for (Id p = lo; p < hi; ++p) {
      Id poly = fc.poly_count[p], at = fc.corner_count[p];
      fans_of(m, pc, p, fan, used, [&](const std::vector<std::uint32_t>& f, bool open) {
        if (!fan_is_polygon(f, open)) return;
        out.offsets[poly++] = static_cast<std::uint64_t>(at);
        for (std::uint32_t corner : f) out.connectivity[at++] = pc.cell_of_corner[corner];
        if (open) out.connectivity[at++] = static_cast<PointIndex>(F + fc.self[p]);
      });
    }
  });
}

}  // namespace

SurfaceMesh dual(const SurfaceMesh& m, DualStats* stats) {
  const analyze::PointCells pc = analyze::point_cells(m);
  const Id V = m.num_points(), F = m.num_cells();
  progress::report("dual: fans", 0.0);
  const int chunks = parallel::chunk_count(V, 1024);
  const FanCounts fc = count_fans(m, pc, chunks);
  if (F + fc.extra > Id{UINT32_MAX} || fc.corners > Id{UINT32_MAX})
    throw LimitError("dual: " + std::to_string(F + fc.extra) + " points or " + std::to_string(fc.corners) +
                     " corners exceed 2^32 - 1");
  SurfaceMesh out;
  dual_points(m, fc, out);
  progress::report("dual: polygons", 0.5);
  dual_polygons(m, pc, fc, chunks, out);
  if (stats) {
    DualStats s;
    s.polygons = fc.polys;
    for (Id p = 0; p < V; ++p) {
      s.boundary_fans += fc.open_fans[p];
      s.nonmanifold_points += fc.fans[p] > 1;
      s.skipped_fans += fc.skipped[p];
    }
    *stats = s;
  }
  return out;
}

}  // namespace keymesh::generate
