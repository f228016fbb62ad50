#pragma once
// The octree nodes one segment's manifest lists, level by level, in the
// order Neuroglancer requires.
//
// Neuroglancer (src/mesh/multiscale.ts, computeOctreeChildOffsets) links
// each listed node at lod k > 0 to the run of listed lod-(k-1) nodes whose
// position >> 1 equals its own, walking both lists in Z-curve order, and
// draws from the root down: a node whose parent is not listed is never
// reached (validateOctree calls it an orphan). So the manifest lists
//   listed(0) = the non-empty lod-0 nodes,
//   listed(k) = the non-empty lod-k nodes plus the parents of listed(k-1),
// a listed node with no mesh of its own being a 0-byte fragment (drawn as
// empty). The top level may hold several nodes: the reader adds the levels
// above it that merge them into one root.
#include <array>
#include <cstdint>
#include <vector>

namespace keymesh::io::neuroglancer {

using NodePosition = std::array<std::uint32_t, 3>;

// Z-curve (Morton) order of x, y, z interleaved with x the least significant
// bit of each level (Neuroglancer's zorder3LessThan).
bool zorder_less(const NodePosition& a, const NodePosition& b);

// listed(k) for every lod from the non-empty nodes of each lod (any order,
// duplicates allowed); each level sorted in Z-curve order, without repeats.
std::vector<std::vector<NodePosition>> listed_nodes(std::vector<std::vector<NodePosition>> nonempty);

}  // namespace keymesh::io::neuroglancer
