// OutputTransaction's staged removals (an output a command makes obsolete,
// as --update does to a segment edited away) and its one-file-twice check,
// now made through a hash of file identities.
#include "keymesh/io/output_transaction.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "keymesh/core/error.hpp"
#include "keymesh/io/atomic_file.hpp"

using namespace keymesh;
namespace fs = std::filesystem;

namespace {

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("keymesh_tx_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void write(const fs::path& path, const std::string& text) {
  io::AtomicFile f(path.string());
  f.write(text);
  f.commit();
}

TEST(OutputTransaction, RemovalHappensAtCommitOnly) {
  const fs::path dir = fresh_dir("removal");
  std::ofstream(dir / "old") << "old";
  {
    io::OutputTransaction outputs;
    outputs.stage_removal((dir / "old").string());
    write(dir / "new", "new");
    EXPECT_TRUE(fs::exists(dir / "old")) << "still there before commit";
  }  // no commit: a failed command
  EXPECT_TRUE(fs::exists(dir / "old"));
  EXPECT_FALSE(fs::exists(dir / "new"));
  {
    io::OutputTransaction outer;
    {
      io::OutputTransaction inner;
      inner.stage_removal((dir / "old").string());
      inner.stage_removal((dir / "never-there").string());  // a missing file is no error
      write(dir / "new", "new");
      inner.commit();
    }
    EXPECT_TRUE(fs::exists(dir / "old")) << "the inner commit hands the removal to the outer transaction";
    outer.commit();
  }
  EXPECT_FALSE(fs::exists(dir / "old"));
  EXPECT_TRUE(fs::exists(dir / "new"));
}

TEST(OutputTransaction, OneFileTwiceThroughTwoSpellingsRefused) {
  const fs::path dir = fresh_dir("twice");
  fs::create_directories(dir / "sub");
  io::OutputTransaction outputs;
  write(dir / "a", "1");
  EXPECT_THROW(write(dir / "sub" / ".." / "a", "2"), InputError);
  write(dir / "b", "3");  // another name is fine
  std::ofstream(dir / "existing") << "x";
  fs::create_hard_link(dir / "existing", dir / "link");
  write(dir / "existing", "4");
  EXPECT_THROW(write(dir / "link", "5"), InputError) << "a hard link is the same file";
  outputs.commit();
  std::ifstream in(dir / "a");
  std::string text;
  in >> text;
  EXPECT_EQ(text, "1") << "the refused second write left the first in place";
}

}  // namespace
