#include "keymesh/io/output_transaction.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "keymesh/core/error.hpp"
#include "keymesh/io/input_file.hpp"

namespace keymesh::io {

namespace {
// Per thread: the CLI opens its transaction on the main thread, where every
// file is committed (workers only encode); Python's threads (a Dask
// scheduler's chunk tasks writing side by side) each stage into their own.
thread_local OutputTransaction* g_current = nullptr;
}  // namespace

OutputTransaction::OutputTransaction() : enclosing_(g_current) { g_current = this; }

OutputTransaction::~OutputTransaction() {
  if (!done_)
    for (const auto& [temporary, destination] : staged_) std::remove(temporary.c_str());
  g_current = enclosing_;
}

OutputTransaction* OutputTransaction::current() { return g_current; }

void OutputTransaction::stage(std::string temporary, std::string destination) {
  // One identity a destination (same_file's test, hashed): a command may
  // stage a file per segment of a large Neuroglancer output.
  if (!identities_.emplace(file_identity(destination), staged_.size()).second) {
    std::remove(temporary.c_str());
    throw InputError(destination + ": written twice by one command (two outputs name the same file)");
  }
  staged_.emplace_back(std::move(temporary), std::move(destination));
}

bool OutputTransaction::staged(const std::string& destination) const {
  return identities_.count(file_identity(destination)) > 0 || (enclosing_ && enclosing_->staged(destination));
}

std::string OutputTransaction::readable(const std::string& destination) const {
  const auto at = identities_.find(file_identity(destination));
  if (at != identities_.end()) return staged_[at->second].first;
  return enclosing_ ? enclosing_->readable(destination) : destination;
}

void OutputTransaction::stage_removal(std::string destination) { removals_.push_back(std::move(destination)); }

void OutputTransaction::commit() {
  if (done_) return;
  done_ = true;
  if (enclosing_) {
    for (auto& [temporary, destination] : staged_) enclosing_->stage(std::move(temporary), std::move(destination));
    for (auto& destination : removals_) enclosing_->stage_removal(std::move(destination));
    return;
  }
  // Renames within one directory do not fail short of a vanished directory;
  // should one fail anyway, the files not yet renamed are removed so that no
  // temporary is left behind.
  for (std::size_t i = 0; i < staged_.size(); ++i)
    if (std::rename(staged_[i].first.c_str(), staged_[i].second.c_str()) != 0) {
      const std::string why = std::strerror(errno);
      for (std::size_t j = i; j < staged_.size(); ++j) std::remove(staged_[j].first.c_str());
      throw InputError(staged_[i].second + ": cannot rename temporary file into place: " + why);
    }
  for (const std::string& destination : removals_)
    if (std::remove(destination.c_str()) != 0 && errno != ENOENT)
      throw InputError(destination + ": cannot remove the obsolete output: " + std::strerror(errno));
}

}  // namespace keymesh::io
