#include "octree_nodes.hpp"

#include <algorithm>

namespace keymesh::io::neuroglancer {

namespace {

// Whether a's highest set bit is below b's.
bool msb_below(std::uint32_t a, std::uint32_t b) { return a < b && a < (a ^ b); }

void sort_unique(std::vector<NodePosition>& nodes) {
  std::sort(nodes.begin(), nodes.end(), zorder_less);
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
}

}  // namespace

bool zorder_less(const NodePosition& a, const NodePosition& b) {
  // The axis whose coordinates differ in the highest bit decides; at equal
  // highest bits z outranks y, and y outranks x.
  int axis = 2;
  for (int candidate : {1, 0})
    if (msb_below(a[axis] ^ b[axis], a[candidate] ^ b[candidate])) axis = candidate;
  return a[axis] < b[axis];
}

std::vector<std::vector<NodePosition>> listed_nodes(std::vector<std::vector<NodePosition>> nonempty) {
  for (std::size_t lod = 1; lod < nonempty.size(); ++lod)
    for (const NodePosition& child : nonempty[lod - 1]) {
      // Parents of every node listed below, which already include theirs.
      nonempty[lod].push_back({child[0] >> 1, child[1] >> 1, child[2] >> 1});
    }
  for (auto& level : nonempty) sort_unique(level);
  return nonempty;
}

}  // namespace keymesh::io::neuroglancer
