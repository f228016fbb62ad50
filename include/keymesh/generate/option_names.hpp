#pragma once
// The names of the generators' option enums, one table per enum. The CLI
// (its CLI11 checks, hence its help), `pipeline` and the Python module parse
// and print the options through these tables, so the names each accepts
// cannot drift apart.
//
//   parse_option<ContourWeld>("keyreduce-sort") == ContourWeld::KeyReduceSort
//   option_name(ContourNormals::Average) == "average"
//   option_names<SubdivideScheme>() == {"linear", "bezier"}   (table order)
//
// A name outside the table is an InputError that lists the table:
// "weld must be 'keyreduce', 'keyreduce-sort' or 'vertexweld', got 'glue'".
#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/labels/labels.hpp"
#include "keymesh/generate/unstructured/subdivide.hpp"

namespace keymesh::generate {

template <class E>
struct OptionName {
  std::string_view name;
  E value;
};

// OptionNames<E>::what names the option in errors; ::table lists the names
// in the order help and errors show them.
template <class E>
struct OptionNames;

template <>
struct OptionNames<ContourNormals> {
  static constexpr std::string_view what = "normals";
  static constexpr std::array<OptionName<ContourNormals>, 3> table{
      {{"none", ContourNormals::None}, {"gradient", ContourNormals::Gradient}, {"average", ContourNormals::Average}}};
};

template <>
struct OptionNames<ContourWeld> {
  static constexpr std::string_view what = "weld";
  static constexpr std::array<OptionName<ContourWeld>, 3> table{{{"keyreduce", ContourWeld::KeyReduce},
                                                                 {"keyreduce-sort", ContourWeld::KeyReduceSort},
                                                                 {"vertexweld", ContourWeld::VertexWeld}}};
};

template <>
struct OptionNames<Backend> {
  static constexpr std::string_view what = "backend";
  static constexpr std::array<OptionName<Backend>, 2> table{{{"cpu", Backend::Cpu}, {"cuda", Backend::Cuda}}};
};

template <>
struct OptionNames<SubdivideScheme> {
  static constexpr std::string_view what = "scheme";
  static constexpr std::array<OptionName<SubdivideScheme>, 2> table{
      {{"linear", SubdivideScheme::Linear}, {"bezier", SubdivideScheme::Bezier}}};
};

// Also the names of tetrahedralize --scheme 24's weld (its face centres by
// face keys or by coordinates): the same two choices.
template <>
struct OptionNames<SubdivideWeld> {
  static constexpr std::string_view what = "weld";
  static constexpr std::array<OptionName<SubdivideWeld>, 2> table{
      {{"keyreduce", SubdivideWeld::KeyReduce}, {"vertexweld", SubdivideWeld::VertexWeld}}};
};

// The command's names of the label generator's methods (keymesh.contour_labels
// takes these and its own, surface_nets and discrete_marching_cubes).
template <>
struct OptionNames<LabelMethod> {
  static constexpr std::string_view what = "method";
  static constexpr std::array<OptionName<LabelMethod>, 2> table{
      {{"surfacenets", LabelMethod::SurfaceNets}, {"discrete-mc", LabelMethod::DiscreteMarchingCubes}}};
};

// The names in table order (what CLI::IsMember takes).
template <class E>
std::vector<std::string> option_names() {
  std::vector<std::string> names;
  for (const auto& entry : OptionNames<E>::table) names.emplace_back(entry.name);
  return names;
}

template <class E>
std::string_view option_name(E value) {
  for (const auto& entry : OptionNames<E>::table)
    if (entry.value == value) return entry.name;
  return "?";  // unreachable for a value of the enum: every one is in its table
}

// The value named `text`, if the table has it.
template <class E>
std::optional<E> find_option(std::string_view text) {
  for (const auto& entry : OptionNames<E>::table)
    if (entry.name == text) return entry.value;
  return std::nullopt;
}

// The value named `text`; InputError listing the names otherwise.
template <class E>
E parse_option(std::string_view text) {
  if (const std::optional<E> value = find_option<E>(text)) return *value;
  // Appended piece by piece: GCC 12 misreads `"'" + std::string(...)` here (-Wrestrict).
  const auto& table = OptionNames<E>::table;
  std::string message(OptionNames<E>::what);
  message.append(" must be ");
  for (std::size_t i = 0; i < table.size(); ++i) {
    if (i > 0) message.append(i + 1 == table.size() ? " or " : ", ");
    message.append(1, '\'').append(table[i].name).append(1, '\'');
  }
  message.append(", got '").append(text).append(1, '\'');
  throw InputError(message);
}

}  // namespace keymesh::generate
