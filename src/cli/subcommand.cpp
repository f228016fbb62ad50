// The one source besides main.cpp that includes CLI11: the subcommands'
// declarations (subcommand.hpp) made as CLI11 calls, with the same types.
#include "subcommand.hpp"

#include <CLI/CLI.hpp>

namespace keymesh::cli {

namespace {
Check made(CLI::Validator validator) { return Check(std::make_shared<const CLI::Validator>(std::move(validator))); }
}  // namespace

Check in_range(int min, int max) { return made(CLI::Range(min, max)); }
Check in_range(long long min, long long max) { return made(CLI::Range(min, max)); }
Check in_range(double min, double max) { return made(CLI::Range(min, max)); }
Check member_of(std::vector<std::string> names) { return made(CLI::IsMember(std::move(names))); }
Check member_of(std::initializer_list<int> values) { return made(CLI::IsMember(values)); }
Check non_negative() { return made(CLI::NonNegativeNumber); }
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
