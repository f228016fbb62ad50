// The one source besides main.cpp that includes CLI11: the subcommands'
// declarations (subcommand.hpp) made as CLI11 calls, with the same types.
#include "subcommand.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <type_traits>

namespace keymesh::cli {

namespace {
Check made(CLI::Validator validator) { return Check(std::make_shared<const CLI::Validator>(std::move(validator))); }

// A bound as the messages write it: %g's shortest form for a double (1e-09,
// where std::to_string writes 0.000000).
template <class T>
std::string bound_text(T bound) {
  std::ostringstream out;
  out << bound;
  return out.str();
}

// CLI11's range (its help text, its reading of the value) with a short
// message: CLI11 2.1 says "Value -1 not in range 0.000000 to 17976931348...
// (309 digits).000000" for NonNegativeNumber, writes 1e-9 as 0.000000, and
// lets "nan" through every double range.
template <class T>
CLI::Validator range_check(CLI::Validator shown, T min, T max) {
  shown.operation([min, max](std::string& text) -> std::string {
    T value{};
    if (!CLI::detail::lexical_cast(text, value))
      return text + (std::is_integral_v<T> ? " is not an integer" : " is not a number");
    if constexpr (std::is_floating_point_v<T>)
      if (!std::isfinite(value)) return text + " is not a finite number";
    if (min <= value && value <= max) return {};
    const bool open = max == std::numeric_limits<T>::max();
    return text + " is out of range (" + bound_text(min) + (open ? " or more)" : " to " + bound_text(max) + ")");
  });
  return shown;
}
}  // namespace

Check in_range(int min, int max) { return made(range_check(CLI::Range(min, max), min, max)); }
Check in_range(long long min, long long max) { return made(range_check(CLI::Range(min, max), min, max)); }
Check in_range(double min, double max) { return made(range_check(CLI::Range(min, max), min, max)); }
Check member_of(std::vector<std::string> names) { return made(CLI::IsMember(std::move(names))); }
Check member_of(std::initializer_list<int> values) {
  // CLI11 2.1 says only "--scheme: x" for a value that is not an integer.
  CLI::Validator shown = CLI::IsMember(values);
  shown.operation([allowed = std::vector<int>(values), names = shown.get_description()](std::string& text) {
    int value = 0;
    const bool read = CLI::detail::lexical_cast(text, value);
    return read && std::find(allowed.begin(), allowed.end(), value) != allowed.end() ? std::string()
                                                                                      : text + " not in " + names;
  });
  return made(shown);
}
Check non_negative() {
  return made(range_check(CLI::NonNegativeNumber, 0LL, std::numeric_limits<long long>::max()));
}
Check text_check(std::function<std::string(std::string&)> check, std::string description) {
  return made(CLI::Validator(std::move(check), std::move(description)));
}

Option* Option::required() {
  option_->required();
  return this;
}
Option* Option::expected(int count) {
  option_->expected(count);
  return this;
}
Option* Option::expected(int min, int max) {
  option_->expected(min, max);
  return this;
}
Option* Option::delimiter(char separator) {
  option_->delimiter(separator);
  return this;
}
Option* Option::needs(Option* other) {
  option_->needs(other->option_);
  return this;
}
Option* Option::check(const Check& check) {
  option_->check(check.validator());
  return this;
}
Option* Option::transform(const Check& check) {
  option_->transform(check.validator());
  return this;
}

std::string Option::get_name() const { return option_->get_name(); }
std::string Option::get_type_name() const { return option_->get_type_name(); }
std::size_t Option::count() const { return option_->count(); }
const std::vector<std::string>& Option::results() const { return option_->results(); }

void Subcommand::description(const std::string& text) { app_->description(text); }

Option* Subcommand::keep(CLI::Option* option) { return &options_.emplace_back(option); }

Option* Subcommand::add_option(const std::string& name, std::string& value, const std::string& help) {
  return keep(app_->add_option(name, value, help));
}
Option* Subcommand::add_option(const std::string& name, int& value, const std::string& help) {
  return keep(app_->add_option(name, value, help));
}
Option* Subcommand::add_option(const std::string& name, long long& value, const std::string& help) {
  return keep(app_->add_option(name, value, help));
}
Option* Subcommand::add_option(const std::string& name, double& value, const std::string& help) {
  return keep(app_->add_option(name, value, help));
}
Option* Subcommand::add_option(const std::string& name, std::vector<long long>& values, const std::string& help) {
  return keep(app_->add_option(name, values, help));
}
Option* Subcommand::add_option(const std::string& name, std::vector<double>& values, const std::string& help) {
  return keep(app_->add_option(name, values, help));
}
Option* Subcommand::add_flag(const std::string& name, bool& value, const std::string& help) {
  return keep(app_->add_flag(name, value, help));
}

std::string Subcommand::get_name() const { return app_->get_name(); }
bool Subcommand::parsed() const { return app_->parsed(); }

const Option* Subcommand::get_option_no_throw(const std::string& name) const {
  const CLI::Option* wanted = app_->get_option_no_throw(name);
  for (const Option& option : options_)
    if (wanted && option.option_ == wanted) return &option;
  return nullptr;
}

}  // namespace keymesh::cli
