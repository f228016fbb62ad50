#pragma once
// Code that may abort() run in a child process. Debian's GDCM is built with
// its assertions on: a malformed DICOM header fails an assert() inside
// gdcm::Reader (found by tests/fuzz/dicom_fuzz.cpp), which would kill the
// command instead of naming the file. run_in_child forks, runs `work` in the
// child and hands its result back through a pipe; InputError and LimitError
// thrown in the child are thrown again in the parent with their message. A
// child that dies (a signal, an abort) becomes the InputError "<what>
// failed (killed by signal 6 (Aborted)): a malformed file"; `what` names the
// file and the library ("dir: IM0001: GDCM").
// The child's stderr is /dev/null (an assert's message would be a second
// line on stderr) and it exits with _exit: no destructors, no atexit
// handlers, no leak check of what the library left behind.
#include <cstddef>
#include <functional>
#include <string>

namespace keymesh::io {

//
// `memory_budget` bytes (0: no bound) bound what the child may map beyond
// the address space it starts with (RLIMIT_AS, in builds without a
// sanitizer, whose shadow memory needs terabytes of it): GDCM allocates
// what a header's length field declares, over 1 GiB for a 1 KB file the
// fuzz target made; past the budget the child fails, the parent reports it.
std::string run_in_child(const std::function<std::string()>& work, const std::string& what,
                         std::size_t memory_budget = 0);

}  // namespace keymesh::io
