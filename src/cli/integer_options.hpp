#pragma once
// Integer options read as typed: CLI11 2.1 reads them with strtoll/strtoull
// and keeps what those return, so a value past 64 bits became the largest
// one (`--labels 99999999999999999999` ran as 9223372036854775807), a
// negative value of an unsigned option wrapped around, and a leading zero
// read as octal (`--smooth 010` ran 8 iterations).
#include <string>

#include "subcommand.hpp"

namespace keymesh::cli {

// Checks every integer option of `cmd` (CLI11 type INT or UINT): a value
// outside the 64-bit range, or negative for an unsigned option, is a usage
// error naming the value as typed; leading zeros are dropped (decimal).
// Narrower types keep CLI11's own range check.
void refuse_out_of_range_integers(Subcommand& cmd);

// The check itself: "" when `text` may go on to CLI11 (rewritten without
// leading zeros), otherwise the reason.
std::string integer_text_error(std::string& text, bool is_unsigned);

}  // namespace keymesh::cli
