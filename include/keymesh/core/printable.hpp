#pragma once
// Text from outside (a file name, a field name) as it may appear inside a
// one-line message: a newline in a file name split the error line in two,
// and a carriage return or escape sequence could overwrite what a terminal
// shows. Control bytes become C escapes (\n, \t, \r, \xNN); everything else,
// UTF-8 included, is kept byte for byte (backslashes too: DICOM values are
// quoted with theirs).
#include <string>
#include <string_view>

namespace keymesh {

std::string printable(std::string_view text);

}  // namespace keymesh
