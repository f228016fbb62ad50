// OutputTransaction's staged removals (an output a command makes obsolete,
// as --update does to a segment edited away) and its one-file-twice check,
// now made through a hash of file identities.
#include "keymesh/io/output_transaction.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <thread>

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

// Each thread has its own open transaction (Dask's threaded scheduler runs
// chunk tasks side by side, each writing through its own): a thread's files
// wait for its own commit, and another thread's transaction neither stages
// nor removes them.
TEST(OutputTransaction, OnePerThread) {
  const fs::path dir = fresh_dir("threads");
  io::OutputTransaction main_thread;
  write(dir / "main", "m");
  std::thread other([&] {
    EXPECT_EQ(io::OutputTransaction::current(), nullptr) << "the main thread's transaction is not this thread's";
    {
      io::OutputTransaction failed;  // destroyed without commit
      write(dir / "failed", "f");
    }
    io::OutputTransaction outputs;
    EXPECT_EQ(io::OutputTransaction::current(), &outputs);
    write(dir / "task", "t");
    EXPECT_FALSE(fs::exists(dir / "task")) << "staged until this thread commits";
    outputs.commit();
  });
  other.join();
  EXPECT_EQ(io::OutputTransaction::current(), &main_thread);
  EXPECT_TRUE(fs::exists(dir / "task"));
  EXPECT_FALSE(fs::exists(dir / "failed"));
  EXPECT_FALSE(fs::exists(dir / "main")) << "the main thread's file waits for its own commit";
  main_thread.commit();
  EXPECT_TRUE(fs::exists(dir / "main"));
}

}  // namespace
