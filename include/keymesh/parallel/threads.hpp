#pragma once
// Thread count of the CPU backend (OpenMP). Every parallel primitive splits
// its range into thread_count() contiguous chunks in a fixed way, so results
// never depend on scheduling: only on the input.
namespace keymesh::parallel {

// The most worker threads anyone may ask for. Output never depends on the
// count, so more threads than cores only costs stacks: 1024 is far past any
// machine this runs on, and well below where libgomp fails to create them.
inline constexpr int kMaxThreads = 1024;

// Sets the number of worker threads; 0 means all cores (at most kMaxThreads).
// Returns the count in force; throws LimitError past kMaxThreads or below 0.
int set_thread_count(int threads);
// The number of worker threads in force (at least 1).
int thread_count();

}  // namespace keymesh::parallel
