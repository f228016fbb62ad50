#pragma once
// Every format spells the scalar types its own way (legacy VTK
// "UNSIGNED_CHAR", numpy's "u1", ...): each keeps one table of its
// spellings, looked up here, instead of a chain of comparisons.
#include <optional>
#include <string_view>

#include "keymesh/mesh/scalar_type.hpp"

namespace keymesh::io {

struct TypeName {
  std::string_view name;
  ScalarType type;
};

// The type `name` spells in `table` (exact match), or nothing.
template <std::size_t N>
std::optional<ScalarType> type_named(std::string_view name, const TypeName (&table)[N]) {
  for (const TypeName& t : table)
    if (t.name == name) return t.type;
  return std::nullopt;
}

}  // namespace keymesh::io
