// A small command-line parser for the mcmt programs (--name value, --name=value, --flag, --help,
// --version)
// and RunMain, which turns exceptions into a one-line "program: error: ..." and exit code 1.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/options.h"

namespace mcmt {

class ArgParser {
 public:
  ArgParser(std::string program, std::string summary);

  // Options keep the value already in *out as their default (shown in --help). A check (core/options.h:
  // InRange, AtLeast, OneOf, ...) is applied to the value given on the command line: a refused value is a
  // usage error naming the option, what it must be and the text given. --help shows it beside the default.
  void AddString(const std::string& name, std::string* out, const std::string& help, bool required = false,
                 TextCheck check = {});
  void AddInt(const std::string& name, int* out, const std::string& help, NumberCheck check = {});
  void AddInt64(const std::string& name, long long* out, const std::string& help, NumberCheck check = {});
  void AddDouble(const std::string& name, double* out, const std::string& help, NumberCheck check = {});
  void AddFlag(const std::string& name, bool* out, const std::string& help);
  // Values of an option that may be repeated (--camera a --camera b).
  void AddList(const std::string& name, std::vector<std::string>* out, const std::string& help);
  // Free text appended to --help (examples, notes).
  void AddEpilog(const std::string& text);
  // --help-config prints this (the Markdown tables of the rig YAML sections the program reads, from their
  // OptionTable declarations) and exits 0.
  void SetConfigHelp(const std::string& markdown) { config_help_ = markdown; }

  // Returns true to go on. Returns false when the program should exit with *exit_code:
  // 0 after --help or --version ("<program> <mcmt::Version()>" on stdout), 2 after a usage error (printed as
  // one line on stderr, naming the option).
  bool Parse(int argc, char** argv, int* exit_code);
  // Was the option given on the command line?
  bool Given(const std::string& name) const;
  std::string Help() const;
  const std::string& program() const { return program_; }

 private:
  struct Option {
    std::string name, help, kind;
    void* out;
    bool required;
    bool given = false;
    std::string default_text;
    std::string check_text;                 // what a value must be ("must be in [0, 1]"); empty: any
    std::function<bool()> check = nullptr;  // whether *out passes the check
  };
  std::string program_, summary_, epilog_, config_help_;
  std::vector<Option> options_;
  Option* Find(const std::string& name);
};

// Runs body(); on an exception prints "<program>: error: <what>" on one line and returns 1.
int RunMain(const std::string& program, const std::function<int()>& body);

}  // namespace mcmt
