// The fold guard's clearance (see label_fold_clearance.hpp).
//
// Why: the guard (label_kernels::GuardStep) tests, for every moving point p
// and each of its triangles (p, q, r), four orientations D(at, q, r) with q
// and r at either end of their moves: twelve per triangle and iteration,
// most of the smoothing's work, though nearly every triangle keeps well
// clear of its least orientation. One bound per triangle proves most of
// them; only the rest are tested, so the guard decides exactly as before.
//
// The bound. With corners a, b, c at present positions a0, b0, c0 moving by
// da, db, dc (each corner at a0 + s da, s in {0, 1}), the orientation
// D = ((b - a) x (c - a)) . n = (a x b + b x c + c x a) . n is
//   D0 + sa (da x (b0 - c0)).n + sb (db x (c0 - a0)).n + sc (dc x (a0 - b0)).n
//      + sa sb (da x db).n + sb sc (db x dc).n + sc sa (dc x da).n,
// and by Cauchy-Schwarz (|n| = 1) at every one of the eight ends
//   D >= D0 - |da||b0 - c0| - |db||c0 - a0| - |dc||a0 - b0|
//         - |da||db| - |db||dc| - |dc||da|  =: B.
// The guard's rotations (p, q, r) of (a, b, c) give the same D.
//
// Rounding. GuardStep computes fl(D(at, q, r)), at = fl(x + fl(1 (c - x)))
// rather than the candidate c itself. With eps = 2^-53, W a bound on every
// side's and move's length and S on every coordinate's magnitude:
//  - |at - c| <= eps (|c - x| + |c|) per axis, and D is linear in p with
//    gradient n x (q - r), |q - r| <= 3 W: at most 3 sqrt(3) eps (W + S) W;
//  - u = q - at and v = r - at are at most 3 W long; each of the six products
//    u_j v_k n_i of D passes at most 7 roundings (two differences, the
//    product, the difference of products, the factor n_i, two sums):
//    |fl(D) - D| <= gamma_7 2 sqrt(3) |u||v| < 25 eps 9 W^2;
//  - B computed here: D0 as GuardStep would (< 25 eps W^2), the six
//    products of lengths (each from a rounded square root, < 8 eps W^2 each)
//    and the seven-term sum (< 6 eps 8 W^2): < 120 eps W^2.
// In all less than 400 eps (W^2 + S W); kSlack takes ten times that, so
// fl(B) >= least + kSlack (W^2 + S W) proves fl(D(at, q, r)) >= least for
// all twelve. A NaN anywhere fails the comparison: not proven, tested.
#include "label_fold_clearance.hpp"

#include <algorithm>
#include <cmath>

#include "keymesh/parallel/for_each.hpp"

namespace keymesh::generate::detail {

namespace {

constexpr double kSlack = 4096 * 0x1p-53;

double length(const double v[3]) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

}  // namespace

bool triangle_clear(const double* a, const double* b, const double* c, double ra, double rb, double rc,
                    const double* n, double least, double size) {
  const double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double ac[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double bc[3] = {c[0] - b[0], c[1] - b[1], c[2] - b[2]};
  const double d0 = (ab[1] * ac[2] - ab[2] * ac[1]) * n[0] + (ab[2] * ac[0] - ab[0] * ac[2]) * n[1] +
                    (ab[0] * ac[1] - ab[1] * ac[0]) * n[2];
  const double lab = length(ab), lac = length(ac), lbc = length(bc);
  const double loss = ra * lbc + rb * lac + rc * lab + ra * rb + rb * rc + rc * ra;
  const double w = std::max({lab, lac, lbc, ra, rb, rc});
  return d0 - loss >= least + kSlack * w * (w + size);
}

void FoldClearance::update(const ClearanceInput& in) {
  reach_.resize(static_cast<std::size_t>(in.points));
  clear_.resize(static_cast<std::size_t>(in.triangles));
  // Each point's move length, and the largest coordinate magnitude (per
  // chunk, then over the chunks: the same for any thread count).
  const int chunks = parallel::chunk_count(in.points, 4096);
  std::vector<double> largest(static_cast<std::size_t>(chunks), 0.0);
  parallel::for_each_chunk(in.points, chunks, [&](Id begin, Id end, int chunk) {
    double m = 0.0;
    for (Id p = begin; p < end; ++p) {
      const double* from = in.x + 3 * p;
      const double* to = in.candidate + 3 * p;
      const double d[3] = {to[0] - from[0], to[1] - from[1], to[2] - from[2]};
      reach_[static_cast<std::size_t>(p)] = length(d);
      for (int a = 0; a < 3; ++a) m = std::max({m, std::fabs(from[a]), std::fabs(to[a])});
    }
    largest[static_cast<std::size_t>(chunk)] = m;
  });
  const double size = *std::max_element(largest.begin(), largest.end());
  parallel::for_each(in.triangles, [&](Id t) {
    const std::uint32_t* c = in.corners + 3 * t;
    clear_[static_cast<std::size_t>(t)] =
        triangle_clear(in.x + 3 * static_cast<Id>(c[0]), in.x + 3 * static_cast<Id>(c[1]),
                       in.x + 3 * static_cast<Id>(c[2]), reach_[c[0]], reach_[c[1]], reach_[c[2]],
                       in.normal + 3 * t, in.least[t], size);
  }, 1024);
}

}  // namespace keymesh::generate::detail
