#include "label_surface_bytes.hpp"

#include <cstdint>
#include <cstring>
#include <string>

#include "keymesh/core/error.hpp"

namespace keymesh::generate::detail {

namespace {

struct Writer {
  std::vector<std::byte>& out;
  void raw(const void* p, std::size_t n) {
    const auto* b = static_cast<const std::byte*>(p);
    out.insert(out.end(), b, b + n);
  }
  void count(std::uint64_t n) { raw(&n, sizeof n); }
  template <class T, class A>
  void array(const std::vector<T, A>& v) {
    count(v.size());
    raw(v.data(), v.size() * sizeof(T));
  }
};

struct Reader {
  const std::vector<std::byte>& in;
  std::size_t at = 0;
  void raw(void* p, std::size_t n) {
    if (n > in.size() - at) throw InputError("labels: a rank's pieces end early (" + std::to_string(in.size()) + " bytes)");
    if (n) std::memcpy(p, in.data() + at, n);  // an empty array's data() may be null: memcpy's UB even for 0
    at += n;
  }
  std::uint64_t count() {
    std::uint64_t n = 0;
    raw(&n, sizeof n);
    return n;
  }
  // A count of items of `size` bytes each that must still be there.
  std::size_t items(std::size_t size) {
    const std::uint64_t n = count();
    if (n > (in.size() - at) / size) throw InputError("labels: a rank's pieces end early");
    return static_cast<std::size_t>(n);
  }
  template <class T, class A>
  void array(std::vector<T, A>& v) {
    v.resize(items(sizeof(T)));
    raw(v.data(), v.size() * sizeof(T));
  }
};

// The arrays of a piece, in the order both directions use.
template <class IO, class Surface>
void arrays(IO& io, Surface& s) {
  io.array(s.mesh.points);
  io.array(s.mesh.connectivity);
  io.array(s.pair);
  io.array(s.junction);
  io.array(s.border_axes);
  io.array(s.cell_centre);
  io.array(s.keys);
  io.array(s.coarse);
}

}  // namespace

void write_pieces(const std::vector<std::vector<LabelSurface>>& pieces, std::vector<std::byte>& out) {
  Writer w{out};
  w.count(pieces.size());
  for (const auto& slab : pieces) {
    w.count(slab.size());
    for (const LabelSurface& s : slab) {
      w.count(s.quads);
      arrays(w, s);
      w.count(s.mesh.cell_fields.size());
      for (const Field& f : s.mesh.cell_fields) {
        w.count(f.name.size());
        w.raw(f.name.data(), f.name.size());
        w.count(static_cast<std::uint64_t>(f.components));
        w.array(f.values);
      }
    }
  }
}

void read_pieces(const std::vector<std::byte>& bytes, std::vector<std::vector<LabelSurface>>& pieces) {
  Reader r{bytes};
  const std::uint64_t slabs = r.count();
  for (std::uint64_t k = 0; k < slabs; ++k) {
    auto& slab = pieces.emplace_back(r.items(1));
    for (LabelSurface& s : slab) {
      s.quads = r.count() != 0;
      arrays(r, s);
      const std::size_t fields = r.items(1);
      for (std::size_t i = 0; i < fields; ++i) {
        Field f;
        f.name.resize(r.items(1));
        r.raw(f.name.data(), f.name.size());
        f.components = static_cast<int>(r.count());
        r.array(f.values);
        s.mesh.cell_fields.push_back(std::move(f));
      }
    }
  }
  if (r.at != bytes.size()) throw InputError("labels: a rank's pieces hold " + std::to_string(bytes.size() - r.at) + " bytes too many");
}

}  // namespace keymesh::generate::detail
