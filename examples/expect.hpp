#pragma once
// The examples' one check: EXPECT(condition) prints the file, line and
// condition and returns 1 from main when the condition is false, so that a
// broken example fails its ctest test.
#include <cstdio>

#define EXPECT(condition)                                                          \
  do {                                                                             \
    if (!(condition)) {                                                            \
      std::fprintf(stderr, "%s:%d: failed: %s\n", __FILE__, __LINE__, #condition); \
      return 1;                                                                    \
    }                                                                              \
  } while (0)
