// Replays the fuzz corpus (tests/fuzz/corpus/<target>/) and every input a
// fuzzer ever crashed on (tests/fuzz/regressions/<target>/) through the
// same target code libFuzzer runs (tests/fuzz/<target>_fuzz.cpp), in the
// ordinary build: each must end in a result that passes the target's checks
// or in InputError/LimitError, never anything else.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "fuzz/fuzz_target.hpp"
// Every target registers itself under its name (see fuzz_target.hpp).
#include "fuzz/den_fuzz.cpp"
#include "fuzz/dicom_fuzz.cpp"
#include "fuzz/legacy_vtk_fuzz.cpp"
#include "fuzz/nifti_fuzz.cpp"
#include "fuzz/nrrd_fuzz.cpp"
#include "fuzz/obj_fuzz.cpp"
#include "fuzz/ply_fuzz.cpp"
#include "fuzz/raw_fuzz.cpp"
#include "fuzz/stl_fuzz.cpp"
#include "fuzz/vti_fuzz.cpp"
#include "fuzz/vtp_fuzz.cpp"
#include "fuzz/vtu_fuzz.cpp"
#include "fuzz/zarr_fuzz.cpp"

namespace {

namespace fs = std::filesystem;

const fs::path kFuzzDir = fs::path(KEYMESH_SOURCE_DIR) / "tests" / "fuzz";

std::vector<fs::path> inputs_of(const std::string& target) {
  std::vector<fs::path> files;
  for (const char* kind : {"corpus", "regressions"}) {
    const fs::path dir = kFuzzDir / kind / target;
    if (!fs::is_directory(dir)) continue;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.is_regular_file()) files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string bytes_of(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

class FuzzReplay : public ::testing::TestWithParam<std::string> {};

TEST_P(FuzzReplay, CorpusAndRegressionsEndCleanly) {
  const std::string target = GetParam();
  const auto body = keymesh::fuzz::registry().at(target);
  const auto files = inputs_of(target);
  ASSERT_FALSE(files.empty()) << "no seed corpus in tests/fuzz/corpus/" << target;
  for (const auto& f : files) {
    SCOPED_TRACE(f.string());
    const std::string data = bytes_of(f);
    EXPECT_NO_THROW(
        keymesh::fuzz::run_guarded(body, reinterpret_cast<const std::uint8_t*>(data.data()), data.size()));
  }
}

// Every target source in the folder is included above, and has a corpus.
TEST(FuzzTargets, EveryTargetIsReplayed) {
  for (const auto& e : fs::directory_iterator(kFuzzDir)) {
    const std::string name = e.path().filename().string();
    const std::string suffix = "_fuzz.cpp";
    if (name.size() <= suffix.size() || name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) continue;
    const std::string target = name.substr(0, name.size() - suffix.size());
    EXPECT_EQ(keymesh::fuzz::registry().count(target), 1u) << name << " is not included in fuzz_replay_test.cpp";
  }
}

std::vector<std::string> target_names() {
  std::vector<std::string> names;
  for (const auto& [name, body] : keymesh::fuzz::registry()) names.push_back(name);
  return names;
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzReplay, ::testing::ValuesIn(target_names()),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });

}  // namespace
