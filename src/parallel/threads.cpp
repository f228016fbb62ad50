#include "keymesh/parallel/threads.hpp"

#include <omp.h>

namespace keymesh::parallel {

namespace {
int g_threads = 0;  // 0: not set yet, use all cores
}

int set_thread_count(int threads) {
  g_threads = threads > 0 ? threads : omp_get_num_procs();
  omp_set_num_threads(g_threads);
  return g_threads;
}

int thread_count() {
  if (g_threads <= 0) set_thread_count(0);
  return g_threads;
}

}  // namespace keymesh::parallel
