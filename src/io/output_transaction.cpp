#include "keymesh/io/output_transaction.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "keymesh/core/error.hpp"
#include "keymesh/io/input_file.hpp"

namespace keymesh::io {

namespace {
// One command runs per process; the CLI opens the transaction on its main
// thread before any worker starts, so a plain pointer is enough.
OutputTransaction* g_current = nullptr;
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
  if (!identities_.insert(file_identity(destination)).second) {
    std::remove(temporary.c_str());
    throw InputError(destination + ": written twice by one command (two outputs name the same file)");
  }
  staged_.emplace_back(std::move(temporary), std::move(destination));
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
