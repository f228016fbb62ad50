#include "keymesh/parallel/threads.hpp"

#include <omp.h>

#include <algorithm>
#include <string>

#include "keymesh/core/error.hpp"

namespace keymesh::parallel {

namespace {
int g_threads = 0;  // 0: not set yet, use all cores
}

int set_thread_count(int threads) {
  if (threads < 0 || threads > max_thread_count())
    throw LimitError("thread count " + std::to_string(threads) + " is outside 0.." +
                     std::to_string(max_thread_count()) + " (0 = all cores)");
  g_threads = threads > 0 ? threads : std::max(omp_get_num_procs(), 1);
  omp_set_num_threads(g_threads);
  return g_threads;
}

int max_thread_count() { return std::max(64, 4 * omp_get_num_procs()); }

int thread_count() {
  if (g_threads <= 0) set_thread_count(0);
  return g_threads;
}

}  // namespace keymesh::parallel
