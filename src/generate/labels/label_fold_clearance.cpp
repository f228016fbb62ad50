// The fold guard's clearance (see label_fold_clearance.hpp).
//
// Why: the guard (label_kernels::GuardStep) tests, for every moving point p
// and each of its triangles (p, q, r), four orientations D(at, q, r) with q
// and r at either end of their moves: twelve per triangle and iteration,
// and as many again on each retry of a shortened move, most of the
// smoothing's work, though nearly every triangle keeps well clear of its
// least orientation. One bound per triangle proves most of them; only the
// rest are tested, so the guard decides exactly as before.
//
// The bound. With corners a, b, c at present positions a0, b0, c0 moving by
// da, db, dc (each corner at a0 + s da, s in [0, 1]), the orientation
// D = ((b - a) x (c - a)) . n = (a x b + b x c + c x a) . n is
//   D0 + sa ga + sb gb + sc gc + sa sb (da x db).n + sb sc (db x dc).n + sc sa (dc x da).n,
//   ga = (da x (b0 - c0)).n, gb = (db x (c0 - a0)).n, gc = (dc x (a0 - b0)).n:
// each corner's move against its opposite side, exactly (a move along the
// normal costs nothing at first order), and the products bounded by
// Cauchy-Schwarz (|n| = 1), so at every one of the eight ends
//   D >= D0 + min(0, ga) + min(0, gb) + min(0, gc) - |da||db| - |db||dc| - |dc||da|  =: B.
// D is linear in each s, so its least over the cube [0, 1]^3 is at one of
// those ends: B bounds D for any fractions of the moves, in particular
// GuardStep's every try (the moving corner at f = 1, 1/2, 1/4 or 1/8 of its
// move, the two others at either end of theirs). The guard's rotations
// (p, q, r) of (a, b, c) give the same D.
//
// Rounding. GuardStep computes fl(D(at, q, r)), at = fl(x + fl(f fl(c - x)))
// (f a power of two: its product is exact) rather than x + f (c - x) itself.
// With eps = 2^-53, every coordinate (present or candidate) at most S in
// magnitude, so that every side and move is at most W = 4 S long
// (2 sqrt(3) S):
//  - |at - (x + f (c - x))| <= eps (|c - x| + S) per axis (the exact point
//    lies between x and c), and D is linear in p with gradient n x (q - r),
//    |q - r| <= 3 W: at most 3 sqrt(3) eps (W + S) W;
//  - u = q - at and v = r - at are at most 3 W long; each of the six products
//    u_j v_k n_i of D passes at most 7 roundings (two differences, the
//    product, the difference of products, the factor n_i, two sums):
//    |fl(D) - D| <= gamma_7 2 sqrt(3) |u||v| < 25 eps 9 W^2;
//  - B computed here: D0 and the g as GuardStep computes D (< 25 eps W^2
//    each), the three products of rounded square roots (< 8 eps W^2 each)
//    and the seven-term sum (< 6 eps 7 W^2): < 200 eps W^2.
// In all less than 500 eps (W^2 + S W) = 10,000 eps S^2; clearance_slack
// takes more than ten times that, 2^-36 S^2, so fl(B) >= least + slack
// proves fl(D(at, q, r)) >= least for all twelve on every try. A NaN or
// infinity in a position or move makes the bound (or the slack) fail the
// comparison: not proven, tested.
#include "label_fold_clearance.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "keymesh/parallel/for_each.hpp"

namespace keymesh::generate::detail {

namespace {

// (u x v) . n
inline double triple(const double u[3], const double v[3], const double* n) {
  return (u[1] * v[2] - u[2] * v[1]) * n[0] + (u[2] * v[0] - u[0] * v[2]) * n[1] + (u[0] * v[1] - u[1] * v[0]) * n[2];
}

// The bound for corners at a, b, c moving by da, db, dc (each |d| long:
// reach), against least + slack.
inline bool clear_bound(const double* a, const double* b, const double* c, const double* da, const double* db,
                        const double* dc, const double reach[3], const double* n, double least, double slack) {
  const double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double ac[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double cb[3] = {b[0] - c[0], b[1] - c[1], b[2] - c[2]};
  const double ga = triple(da, cb, n), gb = triple(db, ac, n), gc = triple(ab, dc, n);
  // Ternaries, not std::fmin: a library call here would spill every register.
  const double bound = triple(ab, ac, n) + (ga < 0 ? ga : 0.0) + (gb < 0 ? gb : 0.0) + (gc < 0 ? gc : 0.0) -
                       (reach[0] * reach[1] + reach[1] * reach[2] + reach[2] * reach[0]);
  return bound >= least + slack;
}

// Triangles [begin, end): clear[t], and clear_point zeroed at the corners of
// the triangles not cleared. A plain loop over local pointers: the byte
// stores may alias anything, which in a lambda over captured references made
// every iteration reload every pointer.
void clear_triangles(const ClearanceInput& in, const FoldClearance::Move* move, double slack, std::uint8_t* clear,
                     std::uint8_t* clear_point, Id begin, Id end) {
  const std::uint32_t* const corners = in.corners;
  const double* const x = in.x;
  const double* const normal = in.normal;
  const double* const least = in.least;
  for (Id t = begin; t < end; ++t) {
    const std::uint32_t* c = corners + 3 * t;
    const FoldClearance::Move &ma = move[c[0]], &mb = move[c[1]], &mc = move[c[2]];
    const double reach[3] = {ma.reach, mb.reach, mc.reach};
    const bool cleared = clear_bound(x + 3 * static_cast<Id>(c[0]), x + 3 * static_cast<Id>(c[1]),
                                     x + 3 * static_cast<Id>(c[2]), ma.d, mb.d, mc.d, reach, normal + 3 * t, least[t],
                                     slack);
    clear[t] = cleared;
    // A corner may be another chunk's too: every write is the same 0.
    if (!cleared)
      for (int k = 0; k < 3; ++k) std::atomic_ref<std::uint8_t>(clear_point[c[k]]).store(0, std::memory_order_relaxed);
  }
}

}  // namespace

double clearance_slack(double size) { return 0x1p-36 * size * size; }

bool triangle_clear(const double* const from[3], const double* const to[3], const double reach[3], const double* n,
                    double least, double slack) {
  double d[3][3];
  for (int k = 0; k < 3; ++k)
    for (int a = 0; a < 3; ++a) d[k][a] = to[k][a] - from[k][a];
  return clear_bound(from[0], from[1], from[2], d[0], d[1], d[2], reach, n, least, slack);
}

void FoldClearance::update(const ClearanceInput& in) {
  move_.resize(static_cast<std::size_t>(in.points));
  clear_.resize(static_cast<std::size_t>(in.triangles));
  clear_point_.assign(static_cast<std::size_t>(in.points), 1);
  // Each point's move and its length, and the largest coordinate magnitude
  // (per chunk, then over the chunks: the same for any thread count).
  const int chunks = parallel::chunk_count(in.points, 4096);
  std::vector<double> largest(static_cast<std::size_t>(chunks), 0.0);
  parallel::for_each_chunk(in.points, chunks, [&](Id begin, Id end, int chunk) {
    const double* const x = in.x;
    const double* const candidate = in.candidate;
    Move* const move = move_.data();
    double m = 0.0;
    for (Id p = begin; p < end; ++p) {
      const double* from = x + 3 * p;
      const double* to = candidate + 3 * p;
      Move& mp = move[p];
      for (int a = 0; a < 3; ++a) mp.d[a] = to[a] - from[a];
      mp.reach = std::sqrt(mp.d[0] * mp.d[0] + mp.d[1] * mp.d[1] + mp.d[2] * mp.d[2]);
      for (int a = 0; a < 3; ++a) m = std::max({m, std::fabs(from[a]), std::fabs(to[a])});
    }
    largest[static_cast<std::size_t>(chunk)] = m;
  });
  const double slack = clearance_slack(*std::max_element(largest.begin(), largest.end()));
  parallel::for_each_chunk(in.triangles, parallel::chunk_count(in.triangles, 1024), [&](Id begin, Id end, int) {
    clear_triangles(in, move_.data(), slack, clear_.data(), clear_point_.data(), begin, end);
  });
}

}  // namespace keymesh::generate::detail
