#pragma once
// Every file one command writes (mesh, pieces, report, index) appears
// together, or none does. While an OutputTransaction is open, AtomicFile's
// commit() only closes its temporary file and stages it here; commit() of the
// transaction renames every staged file into place once the whole command
// has succeeded. Destroyed without commit() (an exception, a non-zero exit),
// it removes every staged temporary: pre-existing files stay untouched and no
// new file is left behind.
//
//   io::OutputTransaction outputs;   // before the first write
//   ... write_mesh(...), write_report(...) ...
//   outputs.commit();                // after the last step that can fail
//
// The CLI opens one around every subcommand (src/cli/main.cpp), so a command
// gets this by writing through AtomicFile as every writer does. Outside a
// transaction (the Python module, tests) AtomicFile renames at once as before.
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace keymesh::io {

class OutputTransaction {
 public:
  // Becomes the open transaction of this thread (they nest: the innermost
  // one stages, and its commit() hands its files to the enclosing one).
  OutputTransaction();
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;
  // Removes the temporaries of files not committed.
  ~OutputTransaction();

  // Renames every staged temporary onto its destination, in the order they
  // were staged; throws InputError naming the destination if one fails.
  void commit();

  // The innermost open transaction, or null.
  static OutputTransaction* current();

  // Called by AtomicFile::commit(): `temporary` is complete and closed. Throws
  // InputError when `destination` is already staged in this transaction
  // (two outputs of one command naming the same file).
  void stage(std::string temporary, std::string destination);

  // Whether `destination` is staged here or in an enclosing transaction (a
  // file this command writes, not on disk before the command commits).
  bool staged(const std::string& destination) const;
  // The file to read for `destination` while the command runs: its staged
  // temporary (here or in an enclosing transaction), else `destination`.
  std::string readable(const std::string& destination) const;

  // An output the command makes obsolete (a Neuroglancer segment edited
  // away): removed at the outermost commit(), after every rename, so that a
  // failed command leaves it in place. A missing file is no error.
  void stage_removal(std::string destination);

 private:
  std::vector<std::pair<std::string, std::string>> staged_;  // (temporary, destination)
  std::unordered_map<std::string, std::size_t> identities_;   // file_identity of every staged destination -> staged_ index
  std::vector<std::string> removals_;
  OutputTransaction* enclosing_ = nullptr;
  bool done_ = false;
};

}  // namespace keymesh::io
