#pragma once
// A subcommand's command line as its source file declares it: options,
// flags, their checks and the help text, through a few of CLI11's own calls
// (the same names and arguments). CLI11 (header-only: every source that
// includes it compiles its validators again, about 6 s of CPU each) is
// included by subcommand.cpp, which makes these calls, and main.cpp, which
// parses; not by the 20-odd sources of the subcommands
// (docs/decisions/ci-time.md).
#include <cstddef>
#include <deque>
#include <functional>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

namespace CLI {
class App;
class Option;
class Validator;
}  // namespace CLI

namespace keymesh::cli {

// A check of an option's value text (a CLI11 validator), made by the
// functions below; the help shows its description.
class Check {
 public:
  explicit Check(std::shared_ptr<const CLI::Validator> validator) : validator_(std::move(validator)) {}
  const CLI::Validator& validator() const { return *validator_; }

 private:
  std::shared_ptr<const CLI::Validator> validator_;
};

// CLI::Range(min, max) as the help shows it: the value read as the bounds'
// type, within them (a double finite), refused in one short line ("x is not
// an integer", "-1 is out of range (0 to 64)").
Check in_range(int min, int max);
Check in_range(long long min, long long max);
Check in_range(double min, double max);
// CLI::IsMember: one of these ("x not in {5,24}").
Check member_of(std::vector<std::string> names);
Check member_of(std::initializer_list<int> values);
// CLI::NonNegativeNumber as the help shows it ("NONNEGATIVE"): an integer,
// 0 or more ("-1 is out of range (0 or more)").
Check non_negative();
// A check of one's own: `check` returns "" to accept the text (which it may
// rewrite, as a transform), otherwise the reason; `description` goes in the
// help beside the option's type ("SIZE").
Check text_check(std::function<std::string(std::string&)> check, std::string description);

// One option of a subcommand (CLI::Option): its settings while declared,
// what was given once parsed.
class Option {
 public:
  explicit Option(CLI::Option* option) : option_(option) {}
  Option* required();
  Option* expected(int count);
  Option* expected(int min, int max);
  Option* delimiter(char separator);
  Option* needs(Option* other);
  Option* check(const Check& check);
  // A check run before the others, which may rewrite the text.
  Option* transform(const Check& check);

  std::string get_name() const;       // "--output", or a positional's name
  std::string get_type_name() const;  // "INT", "TEXT:{a,b}", ...
  std::size_t count() const;          // times given
  const std::vector<std::string>& results() const;  // the values as given

 private:
  friend class Subcommand;
  CLI::Option* option_;
};

// A subcommand (CLI::App) while its file declares its options, then as
// parsed. Not copied: the options' addresses are kept.
class Subcommand {
 public:
  explicit Subcommand(CLI::App& app) : app_(&app) {}
  Subcommand(const Subcommand&) = delete;
  Subcommand& operator=(const Subcommand&) = delete;

  void description(const std::string& text);
  // One per type the subcommands read (CLI11 derives the help's type and
  // the parsing from it).
  Option* add_option(const std::string& name, std::string& value, const std::string& help);
  Option* add_option(const std::string& name, int& value, const std::string& help);
  Option* add_option(const std::string& name, long long& value, const std::string& help);
  Option* add_option(const std::string& name, double& value, const std::string& help);
  Option* add_option(const std::string& name, std::vector<long long>& values, const std::string& help);
  Option* add_option(const std::string& name, std::vector<double>& values, const std::string& help);
  Option* add_flag(const std::string& name, bool& value, const std::string& help);

  std::string get_name() const;
  bool parsed() const;
  // The option declared with `name` among its names, nullptr when none.
  const Option* get_option_no_throw(const std::string& name) const;
  // Every option declared, in order.
  std::deque<Option>& options() { return options_; }

 private:
  Option* keep(CLI::Option* option);

  CLI::App* app_;
  std::deque<Option> options_;
};

}  // namespace keymesh::cli
