// printable() keeps a message on one line whatever a file name holds, and
// changes nothing else (UTF-8 and DICOM's backslashes included).
#include "keymesh/core/printable.hpp"

#include <gtest/gtest.h>

#include <string>

TEST(Printable, EscapesControlBytesOnly) {
  using keymesh::printable;
  EXPECT_EQ(printable("two\nlines.vti"), "two\\nlines.vti");
  EXPECT_EQ(printable("a\tb\rc"), "a\\tb\\rc");
  EXPECT_EQ(printable(std::string("nul\0esc\x1b del\x7f", 13)), "nul\\x00esc\\x1b del\\x7f");
  EXPECT_EQ(printable("caf\xc3\xa9/0\\0\\1e300 ok"), "caf\xc3\xa9/0\\0\\1e300 ok");
  EXPECT_EQ(printable(""), "");
}
