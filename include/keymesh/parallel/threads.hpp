#pragma once
// Thread count of the CPU backend (OpenMP). Every parallel primitive splits
// its range into thread_count() contiguous chunks in a fixed way, so results
// never depend on scheduling: only on the input.
namespace keymesh::parallel {

// The most worker threads anyone may ask for: 4 x the hardware threads, and
// at least 64. Output never depends on the count, so more threads than cores
// only cost time and a stack each (8 MiB of address space with libgomp's
// default): 1024 of them fail to start under a 2 GiB `ulimit -v`, and
// 100,000 kill libgomp outright.
int max_thread_count();

// Sets the number of worker threads; 0 means all cores. Returns the count in
// force; throws LimitError below 0 or past max_thread_count().
int set_thread_count(int threads);
// The number of worker threads in force (at least 1).
int thread_count();

}  // namespace keymesh::parallel
