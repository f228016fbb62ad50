#pragma once
// Thread count of the CPU backend (OpenMP). Every parallel primitive splits
// its range into thread_count() contiguous chunks in a fixed way, so results
// never depend on scheduling: only on the input.
namespace keymesh::parallel {

// Sets the number of worker threads; 0 means all cores. Returns the count in force.
int set_thread_count(int threads);
// The number of worker threads in force (at least 1).
int thread_count();

}  // namespace keymesh::parallel
