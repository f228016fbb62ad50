#pragma once
// The central-difference derivatives at grid points (EdgeInterpolator's
// gradient_at, or derivatives_at when curvature is asked for), each computed
// once for all the cut edges that end at the point instead of once per edge
// end. A grid point ends up to six cut edges: ch2better at iso 90.5 has
// 3.71 M edge ends on 2.07 M distinct grid points, and on the coarse path a
// coarse point is one end of each of its crossings.
//
// A thread's cache of grid rows, direct-mapped: row (j, k) lives in slot
// (k mod 3, j mod 18) with the tag (j, k), and each point of a slot has a
// bit saying whether its derivatives were computed. The structured passes
// walk bricks of 16 rows by a few planes and read the rows around the row
// they write (j - 1 .. j + 1, k - 1 .. k + 1); those rows never share a
// slot, and a brick's rows of the plane above, filled while the plane below
// is written, are still there when their turn comes. The values are those
// gradient_at / derivatives_at return (the same function, the same bits),
// whichever edge asked first.
#include <algorithm>
#include <atomic>
#include <bit>
#include <cstdint>
#include <memory>
#include <vector>

#include "keymesh/core/types.hpp"
#include "keymesh/generate/contour/contour_kernels.hpp"
#include "voxel_bits.hpp"

namespace keymesh::generate {

// A number no other pass over a grid's points has: a thread's
// DerivativeRows drops what it holds when it meets a new one (other
// samples, or another grid).
inline std::uint64_t new_derivative_pass() {
  static std::atomic<std::uint64_t> passes{0};
  return passes.fetch_add(1, std::memory_order_relaxed) + 1;
}

template <class T, bool Hessian>
class DerivativeRows {
 public:
  // Per grid point: the gradient, then (with Hessian) derivatives_at's six
  // second derivatives.
  static constexpr int kValues = Hessian ? 9 : 3;

  // One grid row's slot: at(i) is the derivatives at point (i, j, k).
  class Row {
   public:
    Row() = default;
    Row(const EdgeInterpolator<T>* interp, std::uint64_t* computed, double* values, Id j, Id k)
        : interp_(interp), computed_(computed), values_(values), first_(j * interp->s.nx + k * interp->s.nxy), j_(j),
          k_(k), last_i_(interp->s.nx - 1) {
      const Id jk[3] = {1, j, k};
      interior_row_ = interp->interior(jk);
    }

    [[gnu::always_inline]] const double* at(Id i) const {
      double* const v = values_ + kValues * i;
      std::uint64_t& word = computed_[i >> 6];
      const std::uint64_t bit = std::uint64_t{1} << (i & 63);
      if (!(word & bit)) {
        word |= bit;
        compute(i, v);
      }
      return v;
    }

    // Computes, in a loop of its own, the points of the row with a cut edge
    // to a neighbour (`bits`: the isovalue's inside bits), a superset of
    // the ends of the cut edges the row's and its neighbours' points are
    // on: computed() then reads them with no test (a test taken or not as
    // the surface goes is a branch mispredicted about every other point).
    void compute_edge_ends(const InsideBits& bits) const {
      const GridShape& s = interp_->s;
      const Id words = (s.nx + 63) / 64;
      const std::uint64_t* in = bits.row(j_, k_, s.ny);
      const std::uint64_t* near[4] = {j_ > 0 ? bits.row(j_ - 1, k_, s.ny) : nullptr,
                                      j_ + 1 < s.ny ? bits.row(j_ + 1, k_, s.ny) : nullptr,
                                      k_ > 0 ? bits.row(j_, k_ - 1, s.ny) : nullptr,
                                      k_ + 1 < s.nz ? bits.row(j_, k_ + 1, s.ny) : nullptr};
      std::uint64_t carry = 0;  // bit 63 of the previous word's x cuts
      for (Id q = 0; q < words; ++q) {
        const std::uint64_t a = in[q], next = q + 1 < words ? in[q + 1] : 0;
        std::uint64_t x = a ^ ((a >> 1) | (next << 63));  // bit i: x edge (i, i + 1) cut
        std::uint64_t e = 0;
        for (const std::uint64_t* r : near)
          if (r) e |= a ^ r[q];
        const Id valid = std::min<Id>(64, s.nx - 64 * q);  // points in this word
        const std::uint64_t points = valid == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << valid) - 1;
        if (q + 1 == words) x &= points >> 1;  // no x edge from point nx - 1
        compute_word(q, (e | x | (x << 1) | carry) & points);
        carry = x >> 63;
      }
    }

    // The points of word q of `mask` not computed yet.
    void compute_word(Id q, std::uint64_t mask) const {
      std::uint64_t m = mask & ~computed_[q];
      computed_[q] |= m;
      for (; m; m &= m - 1) {
        const Id i = 64 * q + std::countr_zero(m);
        compute(i, values_ + kValues * i);
      }
    }
    [[gnu::always_inline]] const double* computed(Id i) const { return values_ + kValues * i; }

   private:
    // gradient_at / derivatives_at, their interior test made per row but
    // for i.
    [[gnu::always_inline]] void compute(Id i, double* v) const {
      if (interior_row_ && i > 0 && i < last_i_) {
        if constexpr (Hessian) interp_->interior_derivatives(first_ + i, v, v + 3);
        else interp_->interior_gradient(first_ + i, v);
      } else {
        const Id ijk[3] = {i, j_, k_};
        if constexpr (Hessian) interp_->border_derivatives(first_ + i, ijk, v, v + 3);
        else interp_->border_gradient(first_ + i, ijk, v);
      }
    }

   private:
    const EdgeInterpolator<T>* interp_ = nullptr;
    std::uint64_t* computed_ = nullptr;
    double* values_ = nullptr;
    Id first_ = 0, j_ = 0, k_ = 0, last_i_ = 0;
    bool interior_row_ = false;
  };

  // The calling thread's cache, for `interp` (the same samples and grid
  // throughout pass `pass`; its rows computed through this copy) in pass
  // `pass`.
  static DerivativeRows& of_this_thread(const EdgeInterpolator<T>& interp, std::uint64_t pass) {
    thread_local DerivativeRows rows;
    if (rows.pass_ != pass) rows.start(interp, pass);
    rows.interp_ = &interp;
    return rows;
  }

  // Row (j, k) of the grid.
  Row row(Id j, Id k) {
    const std::size_t slot = static_cast<std::size_t>((k % kPlanes) * kRows + j % kRows);
    std::uint64_t* const computed = computed_.data() + slot * words_;
    if (tag_[slot].j != j || tag_[slot].k != k) {
      tag_[slot] = {j, k};
      std::fill_n(computed, words_, 0);
    }
    return Row(interp_, computed, values_.get() + slot * kValues * nx_, j, k);
  }

 private:
  static constexpr Id kPlanes = 3, kRows = 18;
  struct Tag {
    Id j = -1, k = -1;
  };

  void start(const EdgeInterpolator<T>& interp, std::uint64_t pass) {
    pass_ = pass;
    nx_ = interp.s.nx;
    words_ = static_cast<std::size_t>((nx_ + 63) / 64);
    tag_.assign(static_cast<std::size_t>(kPlanes * kRows), Tag{});
    computed_.resize(static_cast<std::size_t>(kPlanes * kRows) * words_);
    const auto values = static_cast<std::size_t>(kPlanes * kRows * kValues * nx_);
    // Without huge pages (KeptArray's): a surface touches a few points of
    // a row, and each would fault in 2 MB instead of 4 KB.
    if (values > values_size_) values_ = std::make_unique_for_overwrite<double[]>(values), values_size_ = values;
  }

  std::uint64_t pass_ = 0;
  const EdgeInterpolator<T>* interp_ = nullptr;
  Id nx_ = 0;
  std::size_t words_ = 0;
  std::vector<Tag> tag_;
  std::vector<std::uint64_t> computed_;
  std::unique_ptr<double[]> values_;  // kept between calls, grown, never shrunk
  std::size_t values_size_ = 0;
};

}  // namespace keymesh::generate
