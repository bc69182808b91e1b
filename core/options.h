// Options declared once. Each section of the rig YAML (detector, mapper, tracker, sync, logger, viz, lcm)
// is an options struct plus one OptionTable that names, for every member, its key, unit, check and help
// text; the default is the struct's initialiser. The same table loads the section (unknown keys and bad
// values are errors naming file and key), checks options built in code (the same checks), and writes the
// docs table (`mcmt-options --markdown`, used by scripts/gen-process-docs).
//
//   const OptionTable<TrackerOptions>& TrackerOptionTable() {
//     static const auto* t = &(*new OptionTable<TrackerOptions>("tracker"))
//       .Add("huber_px", &TrackerOptions::huber_px, "px", "Huber threshold of the robust loss", Above(0))
//       .Add("channel", &TrackerOptions::channel, "", "output channel", NotEmpty());
//     return *t;
//   }
//   table.Load(rig.tracker, &options);   // from the YAML: throws OptionError "rig.yaml: tracker.huber_px:
//   ..." table.Check(options);                // built in code: throws OptionError "tracker.huber_px: ..."
//
// Adding an option is one Add line. Checks between options (a >= b) or against the rig go in the
// component's own code, throwing OptionError through OptionTable::Fail.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/config.h"

namespace mcmt {

// A bad option: a missing, unknown or malformed key (YamlSection::Fail) or a value its check refuses
// (OptionTable). what(): "<file>: <section>.<key>: <problem>" ("<section>.<key>: <problem>" for options
// built in code). A ConfigError, so callers that catch bad configuration catch it too.
class OptionError : public ConfigError {
 public:
  OptionError(const std::string& file, const std::string& key, const std::string& problem);
  const std::string& file() const { return file_; }
  const std::string& key() const { return key_; }

 private:
  std::string file_, key_;
};

// A check of one value: ok() tells whether it passes, text says what it requires ("must be >= 1").
template <class V>
struct OptionCheck {
  std::string text;
  std::function<bool(const V&)> ok;
};
using NumberCheck = OptionCheck<double>;  // used for int, int64 and double members
using TextCheck = OptionCheck<std::string>;

NumberCheck AtLeast(double lo);                                  // v >= lo
NumberCheck Above(double lo);                                    // v > lo
NumberCheck InRange(double lo, double hi, bool open_lo = false,  // [lo, hi], (lo, hi], [lo, hi), (lo, hi)
                    bool open_hi = false);
TextCheck OneOf(std::vector<std::string> values);  // "expected one of a, b, got 'x'"
TextCheck NotEmpty();

std::string FormatOptionNumber(double v);  // shortest text that reads back the same value

template <class T>
class OptionTable {
 public:
  explicit OptionTable(std::string section) : section_(std::move(section)) {}

  // Where a member lives: Of(&O::huber_px), or in a nested struct Of(&O::scene, &SceneOptions::width).
  template <class M>
  using Ref = std::function<M*(T*)>;
  template <class M>
  static Ref<M> Of(M T::*m) {
    return [m](T* o) { return &(o->*m); };
  }
  template <class S, class M>
  static Ref<M> Of(S T::*outer, M S::*inner) {
    return [outer, inner](T* o) { return &((o->*outer).*inner); };
  }

  OptionTable& Add(const std::string& key, double T::*m, const std::string& unit, const std::string& help,
                   std::optional<NumberCheck> check = {}) {
    return Add(key, Of(m), unit, help, std::move(check));
  }
  OptionTable& Add(const std::string& key, int T::*m, const std::string& unit, const std::string& help,
                   std::optional<NumberCheck> check = {}) {
    return Add(key, Of(m), unit, help, std::move(check));
  }
  OptionTable& Add(const std::string& key, bool T::*m, const std::string& help) {
    return Add(key, Of(m), help);
  }
  OptionTable& Add(const std::string& key, std::string T::*m, const std::string& help,
                   std::optional<TextCheck> check = {}) {
    return Add(key, Of(m), help, std::move(check));
  }
  OptionTable& Add(const std::string& key, Ref<double> r, const std::string& unit, const std::string& help,
                   std::optional<NumberCheck> check = {}) {
    return AddNumber(key, r, unit, help, std::move(check),
                     [](const YamlSection& s, const std::string& k, double d) { return s.GetDouble(k, d); });
  }
  OptionTable& Add(const std::string& key, Ref<int> r, const std::string& unit, const std::string& help,
                   std::optional<NumberCheck> check = {}) {
    return AddNumber(key, r, unit, help, std::move(check),
                     [](const YamlSection& s, const std::string& k, int d) { return s.GetInt(k, d); });
  }
  OptionTable& Add(const std::string& key, Ref<bool> r, const std::string& help) {
    Entry e =
        MakeEntry(key, "", help, "", [r](const T& o) { return std::string(*Get(r, o) ? "true" : "false"); });
    e.load = [r](const YamlSection& s, const std::string& k, T* o) { *r(o) = s.GetBool(k, *r(o)); };
    entries_.push_back(std::move(e));
    return *this;
  }
  OptionTable& Add(const std::string& key, Ref<std::string> r, const std::string& help,
                   std::optional<TextCheck> check = {}) {
    Entry e = MakeEntry(key, "", help, check ? check->text : "", [r](const T& o) { return *Get(r, o); });
    e.load = [r](const YamlSection& s, const std::string& k, T* o) { *r(o) = s.GetString(k, *r(o)); };
    if (check)
      e.check = [r, check](const T& o) -> std::optional<std::string> {
        if (check->ok(*Get(r, o))) return std::nullopt;
        return check->text + ", got '" + *Get(r, o) + "'";
      };
    entries_.push_back(std::move(e));
    return *this;
  }
  // A key kept for old files: read into the same member as `key` (which wins when both are given) after
  // scaling by `scale` (e.g. 1e-3 from a key in microseconds to one in milliseconds). Listed in the docs.
  OptionTable& Deprecated(const std::string& old_key, const std::string& key, double scale = 1.0) {
    for (Entry& e : entries_)
      if (e.key == key) e.old_keys.push_back({old_key, scale});
    return *this;
  }
  // A key read by the component's own code (a list, a value checked against the rig): known, not loaded.
  OptionTable& Other(const std::string& key, const std::string& unit, const std::string& help) {
    entries_.push_back(MakeEntry(key, unit, help, "", [](const T&) { return std::string(); }));
    return *this;
  }

  // Reads the section into *o (members absent from it keep their value), rejects unknown keys (those of
  // `also_known` aside: another table's keys of the same section), then checks every value. Errors name
  // the file and the dotted key.
  void Load(const YamlSection& s, T* o, const std::set<std::string>& also_known = {}) const {
    std::set<std::string> known = Keys();
    known.insert(also_known.begin(), also_known.end());
    s.CheckKnownKeys(known);
    for (const Entry& e : entries_) {
      if (!e.load) continue;
      for (const auto& old : e.old_keys)
        if (s.Has(old.first)) e.load_scaled(s, old.first, old.second, o);
      e.load(s, e.key, o);
    }
    CheckAll(*o, s.file());
  }
  // The same checks for options built in code (file empty) or loaded from `file`.
  void Check(const T& o, const std::string& file = "") const { CheckAll(o, file); }

  [[noreturn]] void Fail(const std::string& file, const std::string& key, const std::string& problem) const {
    throw OptionError(file, section_ + "." + key, problem);
  }

  std::set<std::string> Keys() const {
    std::set<std::string> keys;
    for (const Entry& e : entries_) {
      keys.insert(e.key);
      for (const auto& old : e.old_keys) keys.insert(old.first);
    }
    return keys;
  }
  const std::string& section() const { return section_; }

  // A Markdown table: | key | unit | default | allowed | meaning |, defaults from T{}. (On the heap: GCC 12
  // warns that the string members of a nested option struct on the stack "may be used uninitialized".)
  std::string Markdown() const {
    const auto defaults_owner = std::make_unique<const T>();
    const T& defaults = *defaults_owner;
    std::ostringstream out;
    out << "| `" << section_ << ":` key | unit | default | allowed | meaning |\n|---|---|---|---|---|\n";
    for (const Entry& e : entries_) {
      std::string help = e.help;
      for (const auto& old : e.old_keys) help += " (old key `" + old.first + "` still read, deprecated)";
      const std::string def = e.default_text(defaults);
      out << "| `" << e.key << "` | " << e.unit << " | " << (def.empty() ? "" : "`" + def + "`") << " | "
          << e.check_text << " | " << help << " |\n";
    }
    return out.str();
  }

 private:
  struct Entry {
    std::string key, unit, help, check_text;
    std::function<std::string(const T&)> default_text;
    std::function<void(const YamlSection&, const std::string&, T*)> load;
    std::function<void(const YamlSection&, const std::string&, double, T*)> load_scaled;
    std::function<std::optional<std::string>(const T&)> check;  // the problem, or nothing
    std::vector<std::pair<std::string, double>> old_keys;
  };

  static Entry MakeEntry(const std::string& key, const std::string& unit, const std::string& help,
                         const std::string& check_text, std::function<std::string(const T&)> default_text) {
    Entry e;
    e.key = key;
    e.unit = unit;
    e.help = help;
    e.check_text = check_text;
    e.default_text = std::move(default_text);
    return e;
  }

  template <class M>
  static const M* Get(const Ref<M>& r, const T& o) {  // read access through the same Ref
    return r(const_cast<T*>(&o));
  }

  template <class M, class GetValue>
  OptionTable& AddNumber(const std::string& key, Ref<M> r, const std::string& unit, const std::string& help,
                         std::optional<NumberCheck> check, GetValue get) {
    Entry e = MakeEntry(key, unit, help, check ? check->text : "",
                        [r](const T& o) { return FormatOptionNumber(static_cast<double>(*Get(r, o))); });
    e.load = [r, get](const YamlSection& s, const std::string& k, T* o) { *r(o) = get(s, k, *r(o)); };
    e.load_scaled = [r](const YamlSection& s, const std::string& k, double scale, T* o) {
      *r(o) = static_cast<M>(s.GetDouble(k, 0.0) * scale);
    };
    if (check)
      e.check = [r, check](const T& o) -> std::optional<std::string> {
        const double v = static_cast<double>(*Get(r, o));
        if (check->ok(v)) return std::nullopt;
        return check->text + ", got " + FormatOptionNumber(v);
      };
    entries_.push_back(std::move(e));
    return *this;
  }

  void CheckAll(const T& o, const std::string& file) const {
    for (const Entry& e : entries_)
      if (e.check)
        if (const auto problem = e.check(o)) Fail(file, e.key, *problem);
  }

  std::string section_;
  std::vector<Entry> entries_;
};

// The rig's `sync:` section, shared by the mapper and the tracker (the tracker's own keys override it).
struct SyncOptions {
  double tolerance_ms = 2.0;  // detections this close in utime form one frame
  double deadline_ms = 15.0;  // tracker: a frame is solved at the latest this long after its first detection
  double camera_timeout_s = 1.0;  // tracker: a camera silent this long is not waited for
};
const OptionTable<SyncOptions>& SyncOptionTable();
SyncOptions LoadSyncOptions(const RigConfig& rig);  // throws OptionError naming file and key

// The rig's `lcm:` section.
struct LcmOptions {
  std::string url;  // empty: LCM's default
};
const OptionTable<LcmOptions>& LcmOptionTable();

}  // namespace mcmt
