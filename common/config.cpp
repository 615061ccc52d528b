#include "common/config.h"

#include <spdlog/spdlog.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <limits>
#include <set>
#include <sstream>

namespace slamaware {

struct ConfigFile::Impl {
  YAML::Node root;
};

namespace {

std::string where(const std::string& path, const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.line < 0) return path;
  return path + ":" + std::to_string(mark.line + 1);
}

std::string show(const YAML::Node& node) {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a map";
  return "nothing";
}

// A mapping's key as text; a key that is not a plain scalar (a list, a map, an alias to one) is
// refused naming the file and line.
std::string keyName(const YAML::Node& key, const std::string& file) {
  if (!key.IsScalar())
    throw ConfigError(where(file, key) + ": a key must be a plain name, got " + show(key));
  return key.Scalar();
}

template <class T>
T scalarAs(const YAML::Node& node, const std::string& file, const std::string& key,
           const char* type_name) {
  if (!node.IsScalar()) {
    throw ConfigError(where(file, node) + ": key '" + key + "': expected " + type_name + ", got " +
                      show(node));
  }
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    throw ConfigError(where(file, node) + ": key '" + key + "': expected " + type_name + ", got " +
                      show(node));
  }
}

// yaml-cpp accepts "1.5" as an int by truncation in some versions; be strict.
bool looksIntegral(const std::string& s) {
  if (s.empty()) return false;
  size_t i = (s[0] == '-' || s[0] == '+') ? 1 : 0;
  if (i == s.size()) return false;
  for (; i < s.size(); ++i)
    if (s[i] < '0' || s[i] > '9') return false;
  return true;
}

template <class T>
std::vector<T> listAs(const YAML::Node& node, const std::string& file, const std::string& key,
                      const char* type_name) {
  if (!node.IsSequence()) {
    throw ConfigError(where(file, node) + ": key '" + key + "': expected a list of " + type_name +
                      ", got " + show(node));
  }
  std::vector<T> out;
  for (size_t i = 0; i < node.size(); ++i) {
    const std::string item_key = key + "[" + std::to_string(i) + "]";
    if constexpr (std::is_same_v<T, int>) {
      if (!node[i].IsScalar() || !looksIntegral(node[i].Scalar()))
        throw ConfigError(where(file, node[i]) + ": key '" + item_key +
                          "': expected an integer, got " + show(node[i]));
    }
    out.push_back(scalarAs<T>(node[i], file, item_key, type_name));
  }
  return out;
}

void assign(const OptionList::Field& field, const YAML::Node& node, const std::string& file) {
  const std::string& key = field.key;
  std::visit(
      [&](auto* ptr) {
        using T = std::remove_pointer_t<decltype(ptr)>;
        if constexpr (std::is_same_v<T, bool>) {
          *ptr = scalarAs<bool>(node, file, key, "true or false");
        } else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, int64_t> ||
                             std::is_same_v<T, uint64_t>) {
          if (!node.IsScalar() || !looksIntegral(node.Scalar()))
            throw ConfigError(where(file, node) + ": key '" + key + "': expected an integer, got " +
                              show(node));
          *ptr = scalarAs<T>(node, file, key, "an integer");
        } else if constexpr (std::is_same_v<T, float> || std::is_same_v<T, double>) {
          const T v = scalarAs<T>(node, file, key, "a number");
          if (!std::isfinite(v))
            throw ConfigError(where(file, node) + ": key '" + key +
                              "': expected a finite number, got " + show(node));
          *ptr = v;
        } else if constexpr (std::is_same_v<T, std::string>) {
          *ptr = scalarAs<std::string>(node, file, key, "a string");
        } else if constexpr (std::is_same_v<T, std::vector<int>>) {
          *ptr = listAs<int>(node, file, key, "integers");
        } else if constexpr (std::is_same_v<T, std::vector<double>>) {
          *ptr = listAs<double>(node, file, key, "numbers");
        } else if constexpr (std::is_same_v<T, std::vector<std::string>>) {
          *ptr = listAs<std::string>(node, file, key, "strings");
        }
      },
      field.ref);
}

// Walks `node` and checks that every key (dotted path under `prefix`) names a field or a
// section that holds fields.
void checkKeys(const YAML::Node& node, const std::string& prefix,
               const std::set<std::string>& fields, const std::set<std::string>& sections,
               const std::string& file, const std::string& section) {
  for (const auto& kv : node) {
    const std::string name = keyName(kv.first, file);
    const std::string key = prefix + name;
    if (fields.count(key)) continue;
    if (sections.count(key)) {
      if (!kv.second.IsMap())
        throw ConfigError(where(file, kv.second) + ": key '" + key + "': expected a map, got " +
                          show(kv.second));
      checkKeys(kv.second, key + ".", fields, sections, file, section);
      continue;
    }
    std::string known;
    for (const auto& f : fields) {
      if (f.rfind(prefix, 0) == 0 && f.find('.', prefix.size()) == std::string::npos)
        known += (known.empty() ? "" : ", ") + f.substr(prefix.size());
    }
    throw ConfigError(where(file, kv.first) + ": unknown key '" + key + "'" +
                      (section.empty() ? "" : " in section '" + section + "'") +
                      " (known here: " + known + ")");
  }
}

/// The shortest decimal text that reads back as the same value (0.83, not 0.82999999999999996).
template <class T>
std::string shortestText(T value) {
  std::string text;
  for (int digits = 6; digits <= std::numeric_limits<T>::max_digits10; ++digits) {
    std::ostringstream s;
    s.precision(digits);
    s << value;
    text = s.str();
    std::istringstream back(text);
    T read{};
    back >> read;
    if (read == value) break;
  }
  return text;
}

void emitValue(std::ostringstream& out, const OptionList::Ref& ref) {
  std::visit(
      [&](auto* ptr) {
        using T = std::remove_pointer_t<decltype(ptr)>;
        if constexpr (std::is_same_v<T, bool>) {
          out << (*ptr ? "true" : "false");
        } else if constexpr (std::is_same_v<T, std::string>) {
          YAML::Emitter e;
          e << YAML::DoubleQuoted << *ptr;
          out << e.c_str();
        } else if constexpr (std::is_same_v<T, double> || std::is_same_v<T, float>) {
          out << shortestText(*ptr);
        } else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, int64_t> ||
                             std::is_same_v<T, uint64_t>) {
          out << *ptr;
        } else {
          out << "[";
          for (size_t i = 0; i < ptr->size(); ++i) {
            if (i) out << ", ";
            if constexpr (std::is_same_v<T, std::vector<std::string>>) {
              YAML::Emitter e;
              e << YAML::DoubleQuoted << (*ptr)[i];
              out << e.c_str();
            } else if constexpr (std::is_floating_point_v<typename T::value_type>) {
              out << shortestText((*ptr)[i]);
            } else {
              out << (*ptr)[i];
            }
          }
          out << "]";
        }
      },
      ref);
}

}  // namespace

ConfigFile::ConfigFile(const std::string& path) : path_(path), impl_(std::make_unique<Impl>()) {
  try {
    impl_->root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError(path + ": cannot open config file");
  } catch (const YAML::ParserException& e) {
    throw ConfigError(path + ":" + std::to_string(e.mark.line + 1) +
                      ": YAML syntax error: " + e.msg);
  }
  if (impl_->root.IsNull()) impl_->root = YAML::Node(YAML::NodeType::Map);
  if (!impl_->root.IsMap()) throw ConfigError(path + ": expected a map of keys at the top level");
}

ConfigFile::~ConfigFile() = default;
ConfigFile::ConfigFile(ConfigFile&&) noexcept = default;

bool ConfigFile::hasSection(const std::string& section) const {
  return static_cast<bool>(impl_->root[section]);
}

void ConfigFile::load(const std::string& section, OptionList& list) const {
  // yaml-cpp: Node::operator= writes into the node it refers to; reset() rebinds.
  YAML::Node node;
  node.reset(impl_->root);
  if (!section.empty()) {
    node.reset(impl_->root[section]);
    if (!node || node.IsNull()) return;  // section absent: defaults
    if (!node.IsMap())
      throw ConfigError(where(path_, node) + ": section '" + section + "': expected a map, got " +
                        show(node));
  }
  loadNode(&node, section, list);
}

size_t ConfigFile::listSize(const std::string& section) const {
  const YAML::Node node = impl_->root[section];
  if (!node || node.IsNull()) return 0;
  if (!node.IsSequence())
    throw ConfigError(where(path_, node) + ": section '" + section + "': expected a list, got " +
                      show(node));
  return node.size();
}

void ConfigFile::loadListItem(const std::string& section, size_t index, OptionList& list) const {
  YAML::Node node;
  node.reset(impl_->root[section][index]);
  const std::string what = section + "[" + std::to_string(index) + "]";
  if (!node.IsMap())
    throw ConfigError(where(path_, node) + ": '" + what + "': expected a map, got " + show(node));
  loadNode(&node, what, list);
}

void ConfigFile::loadNode(const void* node_ptr, const std::string& what, OptionList& list) const {
  const YAML::Node& node = *static_cast<const YAML::Node*>(node_ptr);
  std::set<std::string> fields, sections;
  for (const auto& f : list.fields()) {
    fields.insert(f.key);
    for (size_t dot = f.key.find('.'); dot != std::string::npos; dot = f.key.find('.', dot + 1))
      sections.insert(f.key.substr(0, dot));
  }
  checkKeys(node, "", fields, sections, path_, what);
  for (const auto& f : list.fields()) {
    YAML::Node value;
    value.reset(node);
    size_t start = 0;
    bool found = true;
    while (true) {
      const size_t dot = f.key.find('.', start);
      const std::string part = f.key.substr(start, dot == std::string::npos ? dot : dot - start);
      if (!value.IsMap()) {
        found = false;
        break;
      }
      value.reset(value[part]);
      if (!value) {
        found = false;
        break;
      }
      if (dot == std::string::npos) break;
      start = dot + 1;
    }
    if (found) assign(f, value, path_);
  }
}

void ConfigFile::checkSections(const std::vector<std::string>& known) const {
  for (const auto& kv : impl_->root) {
    const std::string name = keyName(kv.first, path_);
    bool ok = false;
    for (const auto& k : known) ok = ok || k == name;
    if (!ok) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      throw ConfigError(where(path_, kv.first) + ": unknown section '" + name +
                        "' (known: " + list + ")");
    }
  }
}

std::string describeOptions(const OptionList& list) {
  std::ostringstream out;
  std::vector<std::string> open;  // currently open section path
  for (const auto& f : list.fields()) {
    std::vector<std::string> parts;
    size_t start = 0;
    for (size_t dot = f.key.find('.'); dot != std::string::npos; dot = f.key.find('.', start)) {
      parts.push_back(f.key.substr(start, dot - start));
      start = dot + 1;
    }
    const std::string leaf = f.key.substr(start);
    size_t common = 0;
    while (common < open.size() && common < parts.size() && open[common] == parts[common]) ++common;
    open.resize(common);
    for (size_t i = common; i < parts.size(); ++i) {
      open.push_back(parts[i]);
      std::string path;
      for (const auto& part : open) path += (path.empty() ? "" : ".") + part;
      const std::string doc = list.sectionDoc(path);
      out << std::string(2 * i, ' ') << parts[i] << ":" << (doc.empty() ? "" : "  # " + doc)
          << "\n";
    }
    out << std::string(2 * parts.size(), ' ') << leaf << ": ";
    emitValue(out, f.ref);
    if (!f.doc.empty()) out << "  # " << f.doc;
    out << "\n";
  }
  return out.str();
}

bool optionsEqual(const OptionList& a, const OptionList& b) {
  if (a.fields().size() != b.fields().size()) return false;
  for (size_t i = 0; i < a.fields().size(); ++i) {
    const auto& fa = a.fields()[i];
    const auto& fb = b.fields()[i];
    if (fa.key != fb.key || fa.ref.index() != fb.ref.index()) return false;
    const bool same = std::visit(
        [&](auto* pa) {
          using P = decltype(pa);
          return *pa == *std::get<P>(fb.ref);
        },
        fa.ref);
    if (!same) return false;
  }
  return true;
}

std::string configFileText(const std::string& section, const OptionList& list) {
  std::ostringstream out;
  out << "# slamaware-" << section
      << " options: the built-in defaults, which the process uses without\n"
      << "# --config. Generated by `slamaware-" << section
      << " --print-config` (make configs); copy it to\n"
      << "# change a value. Each option's documentation is the comment after it.\n";
  for (const std::string& note : list.notes()) {
    // Wrapped at 100 columns as comment lines.
    std::istringstream words(note);
    std::string line = "#";
    for (std::string w; words >> w;) {
      if (line.size() + 1 + w.size() > 100) {
        out << line << "\n";
        line = "#";
      }
      line += " " + w;
    }
    out << line << "\n";
  }
  out << section << ":\n";
  std::istringstream lines(describeOptions(list));
  for (std::string line; std::getline(lines, line);) out << "  " << line << "\n";
  return out.str();
}

void logOptions(const std::string& title, const std::string& source, const OptionList& list) {
  spdlog::info("{} ({}):\n{}", title, source, describeOptions(list));
}

}  // namespace slamaware
