// The multilod writer's manifest, read back field by field as meshes.md
// lays it out, against what the synthetic pieces imply: the listed nodes
// (non-empty ones plus the parents Neuroglancer's octree needs), their
// Z-curve order (a Morton code computed here, bit by bit), the fragment
// sizes summing to the data file, and every fragment decoding (Draco's own
// decoder) to int32 positions inside [0, 2^bits).
#include <draco/compression/decode.h>
#include <gtest/gtest.h>

#include <cstring>
#include <set>

#include "io/neuroglancer/octree_nodes.hpp"
#include "io/neuroglancer_dataset.hpp"
#include "io/neuroglancer_test_files.hpp"
#include "keymesh/io/neuroglancer.hpp"

using namespace keymesh;
using namespace keymesh::tests;
namespace ng = keymesh::io::neuroglancer;
using Node = std::array<std::uint32_t, 3>;

namespace {

// x, y, z bits interleaved, x lowest: a 96-bit code as (high word, low word).
std::pair<std::uint64_t, std::uint64_t> morton(const Node& p) {
  std::uint64_t word[2] = {0, 0};
  for (int bit = 0; bit < 32; ++bit)
    for (int axis = 0; axis < 3; ++axis) {
      const int at = 3 * bit + axis;
      word[at / 64] |= std::uint64_t{(p[axis] >> bit) & 1u} << (at % 64);
    }
  return {word[1], word[0]};
}

class ManifestReader {
 public:
  explicit ManifestReader(std::string bytes) : bytes_(std::move(bytes)) {}
  template <class T>
  T get() {
    EXPECT_LE(at_ + sizeof(T), bytes_.size());
    T v{};
    if (at_ + sizeof(T) <= bytes_.size()) std::memcpy(&v, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  bool at_end() const { return at_ == bytes_.size(); }

 private:
  std::string bytes_;
  std::size_t at_ = 0;
};

struct Manifest {
  float chunk_shape[3], grid_origin[3];
  std::uint32_t num_lods;
  std::vector<float> lod_scales, vertex_offsets;
  std::vector<std::vector<Node>> positions;
  std::vector<std::vector<std::uint32_t>> sizes;
};

Manifest parse_manifest(const std::string& bytes) {
  ManifestReader in(bytes);
  Manifest m;
  for (float& c : m.chunk_shape) c = in.get<float>();
  for (float& o : m.grid_origin) o = in.get<float>();
  m.num_lods = in.get<std::uint32_t>();
  for (std::uint32_t i = 0; i < m.num_lods; ++i) m.lod_scales.push_back(in.get<float>());
  for (std::uint32_t i = 0; i < 3 * m.num_lods; ++i) m.vertex_offsets.push_back(in.get<float>());
  std::vector<std::uint32_t> counts;
  for (std::uint32_t i = 0; i < m.num_lods; ++i) counts.push_back(in.get<std::uint32_t>());
  for (std::uint32_t lod = 0; lod < m.num_lods; ++lod) {
    m.positions.emplace_back(counts[lod]);
    for (int axis = 0; axis < 3; ++axis)  // C order [3, n]: every x, then every y, then every z
      for (Node& p : m.positions.back()) p[axis] = in.get<std::uint32_t>();
    m.sizes.emplace_back();
    for (std::uint32_t i = 0; i < counts[lod]; ++i) m.sizes.back().push_back(in.get<std::uint32_t>());
  }
  EXPECT_TRUE(in.at_end()) << "bytes after the last lod's offsets";
  return m;
}

// The nodes each lod must list for `segment`: non-empty ones and every parent of a listed node.
std::vector<std::set<Node>> expected_nodes(const std::vector<ng::ChunkPiece>& pieces, std::uint64_t segment,
                                           std::vector<std::set<Node>>& nonempty, std::uint32_t lods) {
  nonempty.assign(lods, {});
  for (const auto& p : pieces)
    if (p.segment == segment && !p.triangles.empty())
      nonempty[p.lod].insert({p.chunk[0] >> p.lod, p.chunk[1] >> p.lod, p.chunk[2] >> p.lod});
  std::vector<std::set<Node>> listed = nonempty;
  for (std::uint32_t lod = 1; lod < lods; ++lod)
    for (const Node& c : listed[lod - 1]) listed[lod].insert({c[0] / 2, c[1] / 2, c[2] / 2});
  return listed;
}

void check_fragment(const std::string& bytes, int bits) {
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  ASSERT_TRUE(decoded.ok()) << decoded.status().error_msg_string();
  const std::unique_ptr<draco::Mesh> mesh = std::move(decoded).value();
  const draco::PointAttribute* position = mesh->GetNamedAttribute(draco::GeometryAttribute::POSITION);
  ASSERT_NE(position, nullptr);
  EXPECT_EQ(position->data_type(), draco::DT_INT32);
  EXPECT_EQ(position->num_components(), 3);
  EXPECT_GT(mesh->num_faces(), 0u);
  for (draco::AttributeValueIndex i(0); i < position->size(); ++i) {
    std::int32_t v[3];
    position->GetValue(i, v);
    for (std::int32_t c : v) {
      EXPECT_GE(c, 0);
      EXPECT_LT(c, 1 << bits);
    }
  }
}

TEST(NeuroglancerManifest, FieldsNodesOrderAndFragments) {
  for (int bits : {10, 16}) {
    auto layout = neuroglancer_dataset::layout();
    layout.vertex_quantization_bits = bits;
    const auto pieces = neuroglancer_dataset::pieces(layout, neuroglancer_dataset::boxes());
    const auto dir = neuroglancer_files::fresh_dir("manifest" + std::to_string(bits));
    ng::write_multilod(dir.string(), layout, pieces);
    for (const auto& box : neuroglancer_dataset::boxes()) {
      SCOPED_TRACE("segment " + std::to_string(box.segment));
      const std::string id = std::to_string(box.segment);
      const Manifest m = parse_manifest(neuroglancer_files::bytes_of(dir / (id + ".index")));
      const std::string data = neuroglancer_files::bytes_of(dir / id);
      for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(m.chunk_shape[a], 8.0f);
        EXPECT_EQ(m.grid_origin[a], 0.0f);
      }
      ASSERT_EQ(m.num_lods, 3u);
      EXPECT_EQ(m.lod_scales, (std::vector<float>{1, 2, 4}));
      EXPECT_EQ(m.vertex_offsets, std::vector<float>(9, 0.0f));
      std::vector<std::set<Node>> nonempty;
      const auto listed = expected_nodes(pieces, box.segment, nonempty, 3);
      std::size_t offset = 0;
      for (std::uint32_t lod = 0; lod < 3; ++lod) {
        EXPECT_EQ(std::set<Node>(m.positions[lod].begin(), m.positions[lod].end()), listed[lod]) << "lod " << lod;
        EXPECT_EQ(m.positions[lod].size(), listed[lod].size()) << "a node listed twice";
        for (std::size_t i = 1; i < m.positions[lod].size(); ++i)
          EXPECT_LT(morton(m.positions[lod][i - 1]), morton(m.positions[lod][i])) << "Z-curve order, lod " << lod;
        for (std::size_t i = 0; i < m.positions[lod].size(); ++i) {
          EXPECT_EQ(m.sizes[lod][i] != 0, nonempty[lod].count(m.positions[lod][i]) != 0);
          if (m.sizes[lod][i] != 0) check_fragment(data.substr(offset, m.sizes[lod][i]), bits);
          offset += m.sizes[lod][i];
        }
      }
      EXPECT_EQ(offset, data.size()) << "fragment sizes sum to the data file";
    }
  }
}

TEST(NeuroglancerManifest, ZorderMatchesMortonCode) {
  std::uint64_t state = 12345;
  const auto next = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<std::uint32_t>(state >> 33) >> (state % 29);
  };
  for (int i = 0; i < 20000; ++i) {
    const Node a{next(), next(), next()}, b{next(), next(), next()};
    EXPECT_EQ(ng::zorder_less(a, b), morton(a) < morton(b)) << a[0] << " " << a[1] << " " << a[2];
  }
}

TEST(NeuroglancerManifest, ListedNodesAddParentsOnly) {
  // One lod-0 node at (5, 2, 0) and one lod-2 node elsewhere: lod 1 gains
  // (2, 1, 0), lod 2 gains (1, 0, 0); nothing else is listed.
  const auto listed = ng::listed_nodes({{{5, 2, 0}}, {}, {{0, 1, 1}}});
  EXPECT_EQ(listed[0], (std::vector<Node>{{5, 2, 0}}));
  EXPECT_EQ(listed[1], (std::vector<Node>{{2, 1, 0}}));
  EXPECT_EQ(listed[2], (std::vector<Node>{{1, 0, 0}, {0, 1, 1}}));  // Z order: x=1 (bit 0) before y=1 (bit 1)
}

TEST(NeuroglancerManifest, PointOutsideItsNodeIsAnInternalError) {
  auto layout = neuroglancer_dataset::layout();
  auto pieces = neuroglancer_dataset::pieces(layout, neuroglancer_dataset::boxes());
  pieces[0].points[0] += 9.0f;  // past its chunk (8 samples wide) and past any lod's rounding
  const auto dir = neuroglancer_files::fresh_dir("outside");
  EXPECT_THROW(ng::write_multilod(dir.string(), layout, pieces), std::logic_error);
  EXPECT_TRUE(neuroglancer_files::output_files(dir).empty()) << "nothing written on failure";
}

}  // namespace
