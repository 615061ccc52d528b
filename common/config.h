#pragma once
// Options loading: one options struct per component, one loader for all of them.
//
// An options struct gives each field a default inline and lists its fields in visit():
//
//   struct TrackerOptions {
//     int max_iterations = 10;   ///< Gauss-Newton iterations of pose refinement
//     DepthFilterOptions depth;  ///< a nested section
//     template <class V> void visit(V& v) {
//       v("max_iterations", max_iterations, "Gauss-Newton iterations of pose refinement");
//       v.section("depth", depth);
//     }
//   };
//
// loadConfig<TrackerOptions>(path, "tracker") reads the section "tracker" of a YAML file, rejects
// unknown keys, other top-level sections and ill-typed values with a ConfigError naming key and
// file, and logs the result.
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

namespace slamaware {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A flat description of an options struct: keys (dotted for nested sections), typed pointers
/// into the struct, and the one-line documentation of each.
class OptionList {
 public:
  using Ref = std::variant<bool*, int*, int64_t*, uint64_t*, float*, double*, std::string*,
                           std::vector<int>*, std::vector<double>*, std::vector<std::string>*>;
  struct Field {
    std::string key;  ///< dotted path, e.g. "depth.min_depth"
    Ref ref;
    std::string doc;
  };

  template <class T>
  void operator()(const char* key, T& value, const char* doc) {
    fields_.push_back(Field{prefix_ + key, Ref(&value), doc});
  }
  template <class Sub>
  void section(const char* key, Sub& sub, const char* doc = "") {
    const std::string saved = prefix_;
    prefix_ += std::string(key) + ".";
    if (*doc) section_docs_.emplace_back(prefix_.substr(0, prefix_.size() - 1), doc);
    sub.visit(*this);
    prefix_ = saved;
  }
  /// A remark on the options as a whole (units, conventions): a comment of the config file.
  void note(const char* text) { notes_.emplace_back(text); }
  const std::vector<Field>& fields() const { return fields_; }
  /// The documentation of a section by its dotted key ("" if none).
  std::string sectionDoc(const std::string& key) const {
    for (const auto& [k, d] : section_docs_)
      if (k == key) return d;
    return "";
  }
  const std::vector<std::string>& notes() const { return notes_; }

 private:
  std::string prefix_;
  std::vector<Field> fields_;
  std::vector<std::pair<std::string, std::string>> section_docs_;
  std::vector<std::string> notes_;
};

template <class Options>
OptionList optionListOf(Options& options) {
  OptionList list;
  options.visit(list);
  return list;
}

/// A parsed YAML config file. Sections are loaded one at a time; checkSections() rejects
/// top-level keys that no component claims.
class ConfigFile {
 public:
  /// Parses `path`; throws ConfigError (naming the file and line) on a syntax error or a missing
  /// file.
  explicit ConfigFile(const std::string& path);
  ~ConfigFile();
  ConfigFile(ConfigFile&&) noexcept;
  const std::string& path() const { return path_; }
  bool hasSection(const std::string& section) const;
  /// Loads `section` ("" = the whole file) into the fields of `list`; keys absent from the file
  /// keep their defaults. Throws ConfigError for an unknown key or a value of the wrong type.
  void load(const std::string& section, OptionList& list) const;
  /// Throws ConfigError when the file has a top-level key not in `known`.
  void checkSections(const std::vector<std::string>& known) const;
  /// Number of items of a top-level list section (0 if absent); throws if it is not a list.
  size_t listSize(const std::string& section) const;
  /// Loads item `index` of a top-level list section (a map) like load().
  void loadListItem(const std::string& section, size_t index, OptionList& list) const;

 private:
  void loadNode(const void* node, const std::string& what, OptionList& list) const;
  struct Impl;
  std::string path_;
  std::unique_ptr<Impl> impl_;
};

/// YAML text of the options ("key: value  # doc" per line, nested sections indented).
std::string describeOptions(const OptionList& list);
/// True when every field of `a` equals the same field of `b` (same struct type).
bool optionsEqual(const OptionList& a, const OptionList& b);

/// The text of config/<section>.yaml: a comment naming the process, `section:` and the options
/// below it (describeOptions, indented). The shipped files are generated from the built-in
/// defaults with this (`slamaware-<section> --print-config`, `make configs`), and tests compare.
std::string configFileText(const std::string& section, const OptionList& list);
template <class Options>
std::string defaultConfigFileText(const std::string& section) {
  Options defaults;
  return configFileText(section, optionListOf(defaults));
}

/// Loads `section` of the YAML file at `path` into a default-constructed Options and logs the
/// values. An empty path gives the defaults.
template <class Options>
Options loadConfig(const std::string& path, const std::string& section, bool print = true);

void logOptions(const std::string& title, const std::string& source, const OptionList& list);

template <class Options>
Options loadConfig(const std::string& path, const std::string& section, bool print) {
  Options options;
  OptionList list = optionListOf(options);
  if (!path.empty()) {
    ConfigFile file(path);
    // A component's file holds its section and nothing else: a misspelt section name is refused
    // like a misspelt key, not ignored while the component runs on its defaults.
    if (!section.empty()) file.checkSections({section});
    file.load(section, list);
  }
  if (print)
    logOptions(section.empty() ? "options" : section, path.empty() ? "defaults" : path, list);
  return options;
}

template <class Options>
bool optionsEqual(Options& a, Options& b) {
  return optionsEqual(optionListOf(a), optionListOf(b));
}

}  // namespace slamaware
