#pragma once
// The number of low bits a radix sort must look at for keys up to a bound:
// apart from the sort (radix_sort.hpp) so that the device paths (compiled by
// nvcc too) read it without the CPU's thread headers.
namespace keymesh::parallel {

// Number of bits needed to represent `max_key` (0 for 0).
template <class K>
int bits_needed(K max_key) {
  int b = 0;
  while (b < int(sizeof(K) * 8) && (max_key >> b) != 0) ++b;
  return b;
}

}  // namespace keymesh::parallel
