#include "child_process.hpp"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <new>
#include <stdexcept>

#include "keymesh/core/error.hpp"

namespace keymesh::io {

namespace {

// What the child sends first: how `work` ended.
enum class Outcome : char { Result, Input, Limit, Memory, Other };

bool write_all(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

std::string read_all(int fd) {
  std::string out;
  char buf[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    out.append(buf, static_cast<std::size_t>(n));
  }
  return out;
}

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif
#else
constexpr bool kSanitized = false;
#endif

// Lowers RLIMIT_AS to the address space mapped now plus `budget`.
void limit_memory(std::size_t budget) {
  if (budget == 0 || kSanitized) return;
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  unsigned long long pages = 0;
  const bool read = f && std::fscanf(f, "%llu", &pages) == 1;
  if (f) std::fclose(f);
  if (!read) return;
  const rlim_t limit = static_cast<rlim_t>(pages) * static_cast<rlim_t>(::sysconf(_SC_PAGESIZE)) + budget;
  struct rlimit current {};
  if (::getrlimit(RLIMIT_AS, &current) != 0 || (current.rlim_cur != RLIM_INFINITY && current.rlim_cur <= limit)) return;
  current.rlim_cur = limit;
  ::setrlimit(RLIMIT_AS, &current);
}

[[noreturn]] void run_child(const std::function<std::string()>& work, int fd, std::size_t memory_budget) {
  // The defaults: a fault in the library ends the child (the parent reports
  // it), not a handler the parent installed (a sanitizer's, a fuzzer's).
  for (int sig : {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL}) std::signal(sig, SIG_DFL);
  // The library's own last words (an assert's message) would be a second
  // line on stderr: the parent's error says what failed.
  if (const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC); null >= 0) ::dup2(null, STDERR_FILENO);
  limit_memory(memory_budget);
  Outcome outcome = Outcome::Result;
  std::string payload;
  try {
    payload = work();
  } catch (const LimitError& e) {
    outcome = Outcome::Limit, payload = e.what();
  } catch (const InputError& e) {
    outcome = Outcome::Input, payload = e.what();
  } catch (const std::bad_alloc&) {  // past the budget, or out of memory
    outcome = Outcome::Memory, payload.clear();
  } catch (const std::exception& e) {
    outcome = Outcome::Other, payload = e.what();
  }
  const char head = static_cast<char>(outcome);
  const bool sent = write_all(fd, &head, 1) && write_all(fd, payload.data(), payload.size());
  ::_exit(sent ? 0 : 1);
}

std::string describe(int status) {
  if (WIFSIGNALED(status)) return std::string("killed by signal ") + std::to_string(WTERMSIG(status)) + " (" +
                                 ::strsignal(WTERMSIG(status)) + ")";
  return "exit " + std::to_string(WEXITSTATUS(status));
}

}  // namespace

std::string run_in_child(const std::function<std::string()>& work, const std::string& what,
                         std::size_t memory_budget) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) throw InputError(what + ": cannot make a pipe: " + std::strerror(errno));
  std::fflush(nullptr);  // nothing buffered is written twice
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int err = errno;
    ::close(fds[0]), ::close(fds[1]);
    throw InputError(what + ": cannot start a process: " + std::strerror(err));
  }
  if (pid == 0) {
    ::close(fds[0]);
    run_child(work, fds[1], memory_budget);
  }
  ::close(fds[1]);
  std::string got = read_all(fds[0]);
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || got.empty())
    throw InputError(what + " failed (" + describe(status) + "): a malformed file");
  const auto outcome = static_cast<Outcome>(got[0]);
  got.erase(0, 1);
  switch (outcome) {
    case Outcome::Result: return got;
    case Outcome::Input: throw InputError(got);
    case Outcome::Limit: throw LimitError(got);
    case Outcome::Memory:
      if (memory_budget == 0) throw std::bad_alloc();
      throw InputError(what + " needed more than " + std::to_string(memory_budget >> 20) +
                       " MiB for it: a malformed file");
    case Outcome::Other: break;
  }
  throw std::runtime_error(got);
}

}  // namespace keymesh::io
