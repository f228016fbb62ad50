#include "output_files.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <regex>
#include <set>

#include "info_json.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/io/atomic_file.hpp"
#include "keymesh/io/output_transaction.hpp"
#include "keymesh/parallel/for_each_task_beside.hpp"

namespace keymesh::io::neuroglancer {

namespace {

namespace fs = std::filesystem;

void write_file(const fs::path& path, const std::string& bytes) {
  AtomicFile file(path.string());
  file.write(bytes);
  file.commit();
}

void remove_at_commit(const fs::path& path) {
  std::error_code ec;
  if (fs::exists(path, ec)) OutputTransaction::current()->stage_removal(path.string());
}

// The earlier outputs in DIR that `written` does not hold.
void remove_stale(const fs::path& dir, const std::set<std::string>& written) {
  static const std::regex ours("[0-9]+(\\.index)?|[0-9a-f]+\\.shard");
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_regular_file(ec) && std::regex_match(name, ours) && !written.count(name)) remove_at_commit(entry.path());
  }
}

void write_unsharded(const fs::path& dir, const std::vector<SegmentFiles>& segments, const OutputScope& scope,
                     std::set<std::string>& written) {
  for (const SegmentFiles& s : segments) {
    const std::string id = std::to_string(s.segment);
    write_file(dir / (id + ".index"), s.manifest);
    write_file(dir / id, s.data);
    written.insert(id + ".index");
    written.insert(id);
  }
  for (std::uint64_t segment : scope.segments)
    for (const std::string& name : {std::to_string(segment) + ".index", std::to_string(segment)})
      if (!written.count(name)) remove_at_commit(dir / name);
}

void write_sharded(const fs::path& dir, const ShardingSpec& spec, const std::vector<SegmentFiles>& segments,
                   const OutputScope& scope, std::set<std::string>& written) {
  std::map<std::uint64_t, std::vector<const SegmentFiles*>> shards;
  for (const SegmentFiles& s : segments) shards[shard_of(spec, s.segment)].push_back(&s);
  for (const auto& [shard, members] : shards) {
    const std::string name = shard_file_name(spec, shard);
    write_file(dir / name, shard_bytes(spec, members));
    written.insert(name);
  }
  for (std::uint64_t shard : scope.shards)
    if (!shards.count(shard)) remove_at_commit(dir / shard_file_name(spec, shard));
}

}  // namespace

std::vector<SegmentFiles> encode_segments(const MultilodLayout& layout,
                                          const std::vector<std::pair<std::uint64_t, std::vector<const ChunkPiece*>>>& groups,
                                          const std::function<void()>& beside) {
  std::vector<SegmentFiles> files(groups.size());
  // The first segment's error, whatever the thread count.
  parallel::for_each_task_beside(
      static_cast<Id>(groups.size()), [&](Id i) { files[i] = encode_segment(layout, groups[i].first, groups[i].second); },
      [&] {
        if (beside) beside();
      });
  std::erase_if(files, [](const SegmentFiles& f) { return f.manifest.empty(); });
  return files;
}

std::optional<ShardingSpec> sharding_of(const MultilodLayout& layout, std::size_t segments) {
  if (!layout.sharded) return std::nullopt;
  return sharding_for(segments);
}

OutputParts::OutputParts(const std::string& dir, const MultilodLayout& layout, const SegmentNames& names,
                         const std::optional<ShardingSpec>& sharding)
    : dir_(dir), sharding_(sharding), written_{"info"} {
  const fs::path root(dir);
  std::error_code ec;
  fs::create_directories(root, ec);
  if (ec) throw InputError(dir + ": cannot create the output directory: " + ec.message());
  write_file(root / "info", info_json(layout, sharding, !names.empty()));
  const fs::path properties = root / kSegmentPropertiesDir / "info";
  if (!names.empty()) {
    fs::create_directories(properties.parent_path(), ec);
    if (ec) throw InputError(properties.parent_path().string() + ": cannot create it: " + ec.message());
    write_file(properties, segment_properties_json(names));
  } else {
    remove_at_commit(properties);
  }
}

void OutputParts::add(const std::vector<SegmentFiles>& segments, const OutputScope& scope) {
  if (sharding_)
    write_sharded(dir_, *sharding_, segments, scope, written_);
  else
    write_unsharded(dir_, segments, scope, written_);
}

void OutputParts::finish() { remove_stale(dir_, written_); }

void write_output(const std::string& dir, const MultilodLayout& layout, const std::vector<SegmentFiles>& segments,
                  const SegmentNames& names, const std::optional<ShardingSpec>& sharding, const OutputScope& scope) {
  OutputParts parts(dir, layout, names, sharding);
  parts.add(segments, scope);
  if (scope.full) parts.finish();
}

}  // namespace keymesh::io::neuroglancer
