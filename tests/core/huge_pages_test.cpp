// The environment of the huge-page re-exec (core/huge_pages.hpp), built
// from envp alone as the preinit step must: what is added, what is kept,
// and every case that must not re-exec.
#include "keymesh/core/huge_pages.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

namespace {

// The environment huge_pages_environment makes of `vars` (none: no re-exec).
std::unique_ptr<std::vector<std::string>> reexec_environment(std::vector<std::string> vars) {
  std::vector<char*> envp;
  for (std::string& v : vars) envp.push_back(v.data());
  envp.push_back(nullptr);
  char** env = keymesh::huge_pages_environment(envp.data());
  if (!env) return nullptr;
  auto out = std::make_unique<std::vector<std::string>>();
  for (char** e = env; *e; ++e) out->emplace_back(*e);
  std::free(env);
  return out;
}

TEST(HugePagesEnvironment, AddsTheTunableAndTheMark) {
  const auto env = reexec_environment({"HOME=/root", "PATH=/bin"});
  ASSERT_TRUE(env);
  EXPECT_EQ(*env, (std::vector<std::string>{"HOME=/root", "PATH=/bin", "GLIBC_TUNABLES=glibc.malloc.hugetlb=1",
                                            "KEYMESH_HUGE_PAGES_REEXEC=1"}));
}

TEST(HugePagesEnvironment, ExtendsOtherTunablesInPlace) {
  const auto env = reexec_environment({"A=1", "GLIBC_TUNABLES=glibc.malloc.arena_max=2", "B=2"});
  ASSERT_TRUE(env);
  EXPECT_EQ(*env, (std::vector<std::string>{"A=1", "GLIBC_TUNABLES=glibc.malloc.arena_max=2:glibc.malloc.hugetlb=1",
                                            "B=2", "KEYMESH_HUGE_PAGES_REEXEC=1"}));
  const auto empty = reexec_environment({"GLIBC_TUNABLES="});
  ASSERT_TRUE(empty);
  EXPECT_EQ(*empty, (std::vector<std::string>{"GLIBC_TUNABLES=glibc.malloc.hugetlb=1", "KEYMESH_HUGE_PAGES_REEXEC=1"}));
}

TEST(HugePagesEnvironment, NoReexecWhenOffSetOrTried) {
  EXPECT_FALSE(reexec_environment({"KEYMESH_HUGE_PAGES=0"}));
  EXPECT_FALSE(reexec_environment({"GLIBC_TUNABLES=glibc.malloc.hugetlb=0"}));  // the user's own setting
  EXPECT_FALSE(reexec_environment({"GLIBC_TUNABLES=glibc.malloc.arena_max=2:glibc.malloc.hugetlb=2"}));
  EXPECT_FALSE(reexec_environment({"KEYMESH_HUGE_PAGES_REEXEC=1"}));  // a libc that ignored the tunable
  EXPECT_TRUE(reexec_environment({"KEYMESH_HUGE_PAGES=1"}));
}

TEST(HugePagesEnvironment, NamesMatchWhole) {
  // Longer names that start alike are other variables.
  const auto env = reexec_environment({"KEYMESH_HUGE_PAGES_X=0", "GLIBC_TUNABLES_OLD=glibc.malloc.hugetlb=1"});
  ASSERT_TRUE(env);
  EXPECT_EQ(env->size(), 4u);
  EXPECT_EQ((*env)[2], "GLIBC_TUNABLES=glibc.malloc.hugetlb=1");
}

TEST(HugePagesEnvironment, NoEnvironmentAtAll) {
  char** env = keymesh::huge_pages_environment(nullptr);
  ASSERT_NE(env, nullptr);
  EXPECT_EQ(std::string(env[0]), "GLIBC_TUNABLES=glibc.malloc.hugetlb=1");
  EXPECT_EQ(std::string(env[1]), "KEYMESH_HUGE_PAGES_REEXEC=1");
  EXPECT_EQ(env[2], nullptr);
  std::free(env);
}

}  // namespace
