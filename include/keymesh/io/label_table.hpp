#pragma once
// Label tables: the names of a segmentation's labels, one "ID NAME" a line,
// as the atlases of Debian's mricron-data ship them beside the volume
// (aal.nii.gz with aal.nii.txt: "1 Precentral_L 2001", or tab-separated
// "0<TAB>Unclassified"). Further columns, blank lines and lines starting with
// '#' are ignored; the id is a non-negative decimal integer.
#include <cstdint>
#include <map>
#include <string>

namespace keymesh::io {

// Refused (InputError naming the file and line): an unreadable file, a line
// whose first column is not a non-negative integer below 2^64 or that has no
// name, an id given twice.
std::map<std::uint64_t, std::string> read_label_table(const std::string& path);

// The table beside a volume, as MRIcron names it: VOLUME.txt, or VOLUME
// without its .gz then .txt ("aal.nii.gz" -> "aal.nii.txt"); empty when
// neither exists.
std::string label_table_beside(const std::string& volume_path);

}  // namespace keymesh::io
