#include "core/cli.h"

#include <cstdlib>
#include <exception>
#include <iostream>
#include <sstream>

#include "core/version.h"

namespace mcmt {

ArgParser::ArgParser(std::string program, std::string summary)
    : program_(std::move(program)), summary_(std::move(summary)) {}

namespace {

template <class V, class C>
std::function<bool()> Bound(const OptionCheck<C>& check, V* out) {
  if (!check.ok) return nullptr;
  return [ok = check.ok, out]() { return ok(static_cast<C>(*out)); };
}

}  // namespace

void ArgParser::AddString(const std::string& name, std::string* out, const std::string& help, bool required,
                          TextCheck check) {
  options_.push_back({name, help, "string", out, required, false, *out, check.text, Bound(check, out)});
}
void ArgParser::AddInt(const std::string& name, int* out, const std::string& help, NumberCheck check) {
  options_.push_back(
      {name, help, "int", out, false, false, std::to_string(*out), check.text, Bound(check, out)});
}
void ArgParser::AddInt64(const std::string& name, long long* out, const std::string& help,
                         NumberCheck check) {
  options_.push_back(
      {name, help, "int64", out, false, false, std::to_string(*out), check.text, Bound(check, out)});
}
void ArgParser::AddDouble(const std::string& name, double* out, const std::string& help, NumberCheck check) {
  std::ostringstream s;
  s << *out;
  options_.push_back({name, help, "double", out, false, false, s.str(), check.text, Bound(check, out)});
}
void ArgParser::AddFlag(const std::string& name, bool* out, const std::string& help) {
  options_.push_back({name, help, "flag", out, false, false, "", "", nullptr});
}
void ArgParser::AddList(const std::string& name, std::vector<std::string>* out, const std::string& help) {
  options_.push_back({name, help, "list", out, false, false, "", "", nullptr});
}
void ArgParser::AddEpilog(const std::string& text) { epilog_ += text; }

ArgParser::Option* ArgParser::Find(const std::string& name) {
  for (auto& o : options_)
    if (o.name == name) return &o;
  return nullptr;
}

bool ArgParser::Given(const std::string& name) const {
  for (const auto& o : options_)
    if (o.name == name) return o.given;
  return false;
}

std::string ArgParser::Help() const {
  std::ostringstream s;
  s << "usage: " << program_;
  for (const auto& o : options_) {
    if (o.required) s << " --" << o.name << " " << (o.kind == "flag" ? "" : "VALUE");
  }
  s << " [options]\n" << summary_ << "\n\noptions:\n";
  for (const auto& o : options_) {
    std::string left = "  --" + o.name +
                       (o.kind == "flag" ? "" : " " + std::string(o.kind == "list" ? "VALUE..." : "VALUE"));
    s << left;
    if (left.size() < 28)
      s << std::string(28 - left.size(), ' ');
    else
      s << "\n" << std::string(28, ' ');
    s << o.help;
    if (o.required)
      s << " (required" << (o.check_text.empty() ? "" : "; " + o.check_text) << ")";
    else if (!o.default_text.empty())
      s << " (default: " << o.default_text << (o.check_text.empty() ? "" : "; " + o.check_text) << ")";
    else if (!o.check_text.empty())
      s << " (" << o.check_text << ")";
    s << "\n";
  }
  s << "  --help                    print this help and exit\n";
  s << "  --version                 print the version and exit\n";
  if (!config_help_.empty())
    s << "  --help-config             print the rig YAML keys this program reads (Markdown) and exit\n";
  if (!epilog_.empty()) s << "\n" << epilog_ << (epilog_.back() == '\n' ? "" : "\n");
  return s.str();
}

static bool ParseNumber(const std::string& text, const std::string& kind, void* out) {
  char* end = nullptr;
  errno = 0;
  if (kind == "double") {
    double v = std::strtod(text.c_str(), &end);
    if (end == text.c_str() || *end != '\0' || errno) return false;
    *static_cast<double*>(out) = v;
  } else {
    long long v = std::strtoll(text.c_str(), &end, 10);
    if (end == text.c_str() || *end != '\0' || errno) return false;
    if (kind == "int") {
      if (v < INT32_MIN || v > INT32_MAX) return false;
      *static_cast<int*>(out) = static_cast<int>(v);
    } else {
      *static_cast<long long*>(out) = v;
    }
  }
  return true;
}

bool ArgParser::Parse(int argc, char** argv, int* exit_code) {
  auto usage_error = [&](const std::string& what) {
    std::cerr << program_ << ": error: " << what << " (see --help)" << std::endl;
    *exit_code = 2;
    return false;
  };
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << Help();
      *exit_code = 0;
      return false;
    }
    if (arg == "--help-config" && !config_help_.empty()) {
      std::cout << config_help_;
      *exit_code = 0;
      return false;
    }
    if (arg == "--version") {
      std::cout << program_ << " " << Version() << "\n";
      *exit_code = 0;
      return false;
    }
    if (arg.rfind("--", 0) != 0) return usage_error("unexpected argument '" + arg + "'");
    std::string name = arg.substr(2), value;
    bool has_value = false;
    if (auto eq = name.find('='); eq != std::string::npos) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
      has_value = true;
    }
    Option* o = Find(name);
    if (!o) return usage_error("unknown option --" + name);
    o->given = true;
    if (o->kind == "flag") {
      if (has_value) return usage_error("--" + name + " takes no value");
      *static_cast<bool*>(o->out) = true;
      continue;
    }
    if (!has_value) {
      if (i + 1 >= argc) return usage_error("--" + name + " needs a value");
      value = argv[++i];
    }
    if (o->kind == "string") {
      *static_cast<std::string*>(o->out) = value;
    } else if (o->kind == "list") {
      static_cast<std::vector<std::string>*>(o->out)->push_back(value);
    } else if (!ParseNumber(value, o->kind, o->out)) {
      return usage_error("--" + name + ": expected " + (o->kind == "double" ? "a number" : "an integer") +
                         ", got '" + value + "'");
    }
    if (o->check && !o->check())
      return usage_error("--" + name + ": " + o->check_text + ", got '" + value + "'");
  }
  for (const auto& o : options_)
    if (o.required && !o.given) return usage_error("missing required option --" + o.name);
  return true;
}

int RunMain(const std::string& program, const std::function<int()>& body) {
  try {
    return body();
  } catch (const std::exception& e) {
    std::string what = e.what();
    for (char& c : what)
      if (c == '\n') c = ' ';
    std::cerr << program << ": error: " << what << std::endl;
    return 1;
  }
}

}  // namespace mcmt
