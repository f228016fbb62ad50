#pragma once
// What the bench programs (contour_bench, ops_bench, peers/thrust_weld) share:
// the options every one of them takes and the timing columns every JSON line
// ends with, in the order bench/run.py and bench/report.py read them.
#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace keymesh::bench {

struct CommonOptions {
  long long size = 256;  // the sphere's size; a --file's largest dimension once read
  int threads = 0;       // 0: all cores
  int reps = 5;
  double iso = -1;  // -1: the program's default for the sphere
  std::string file;  // a volume file instead of the sphere (needs --iso)
};

// Parses "--name value" pairs. `own(name, value)` sees each option first and
// returns true for the program's own ones; the rest must be common ones. On
// an unknown option, or --file without --iso, prints why and returns exit
// status 2; else 0.
template <class Own>
int parse_options(int argc, char** argv, CommonOptions& o, Own&& own) {
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    const char* value = argv[i + 1];
    if (own(a, value)) continue;
    if (a == "--size") o.size = std::atoll(value);
    else if (a == "--threads") o.threads = std::atoi(value);
    else if (a == "--reps") o.reps = std::atoi(value);
    else if (a == "--iso") o.iso = std::atof(value);
    else if (a == "--file") o.file = value;
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  if (!o.file.empty() && o.iso < 0) {
    std::fprintf(stderr, "--file needs --iso\n");
    return 2;
  }
  if (o.reps < 1) {  // the timing columns need a run
    std::fprintf(stderr, "--reps must be 1 or more\n");
    return 2;
  }
  return 0;
}

// The isovalue the paper contours the Spherical Distance field of `size` at.
inline double sphere_iso(long long size) { return static_cast<double>(size / 2) - 1 + 0.001; }

// The median of the repetitions' seconds (the upper middle of an even count).
inline double median(std::vector<double> times) {
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

// The JSON columns of the repetitions' seconds, `times` in run order (the
// first is the cold run: fresh memory, as in a one-shot CLI), each name
// after `prefix`: "median":…,"min":…,"max":…,"first":…,"reps":N (no
// braces, no trailing comma).
inline std::string timing_json(std::vector<double> times, const char* prefix = "") {
  const double first = times.front();
  std::sort(times.begin(), times.end());
  char text[256];
  std::snprintf(text, sizeof text, "\"%smedian\":%.6f,\"%smin\":%.6f,\"%smax\":%.6f,\"%sfirst\":%.6f,\"%sreps\":%d",
                prefix, times[times.size() / 2], prefix, times.front(), prefix, times.back(), prefix, first, prefix,
                static_cast<int>(times.size()));
  return text;
}

// The process's peak RSS so far, MiB (Linux reports KiB).
inline double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

}  // namespace keymesh::bench
