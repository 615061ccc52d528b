#include "tools/report/report_markdown.h"

#include <cstdio>
#include <map>
#include <set>
#include <sstream>

namespace slamaware {

namespace {

std::string cell(const nlohmann::json& v) {
  if (v.is_null()) return "–";
  if (v.is_number_float()) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.4g", v.get<double>());
    return buf;
  }
  if (v.is_string()) return v.get<std::string>();
  if (v.is_primitive()) return v.dump();
  return "…";
}

// Scalars of an object, flattened with dotted keys (nested objects one level deep).
void flatten(const nlohmann::json& obj, const std::string& prefix, std::map<std::string, nlohmann::json>& out,
             int depth) {
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
    if (it->is_object() && depth > 0)
      flatten(*it, key, out, depth - 1);
    else if (!it->is_structured())
      out[key] = *it;
  }
}

}  // namespace

std::string renderMarkdown(const nlohmann::json& report) {
  std::ostringstream md;
  md << "# slamaware report\n\n";
  // Per-sequence sections: one table per section name, a row per sequence.
  if (report.contains("sequences") && report["sequences"].is_object()) {
    std::set<std::string> sections;
    for (auto& [name, seq] : report["sequences"].items())
      for (auto& [section, v] : seq.items())
        if (v.is_object()) sections.insert(section);
    for (const auto& section : sections) {
      std::map<std::string, std::map<std::string, nlohmann::json>> rows;
      std::set<std::string> columns;
      for (auto& [name, seq] : report["sequences"].items()) {
        if (!seq.contains(section)) continue;
        flatten(seq[section], "", rows[name], 1);
        for (auto& kv : rows[name]) columns.insert(kv.first);
      }
      if (report.contains("overall") && report["overall"].contains(section)) {
        flatten(report["overall"][section], "", rows["**overall**"], 1);
        for (auto& kv : rows["**overall**"]) columns.insert(kv.first);
      }
      md << "## " << section << "\n\n| sequence |";
      for (const auto& c : columns) md << " " << c << " |";
      md << "\n|---|";
      for (size_t i = 0; i < columns.size(); ++i) md << "---|";
      md << "\n";
      for (auto& [name, row] : rows) {
        md << "| " << name << " |";
        for (const auto& c : columns) md << " " << (row.count(c) ? cell(row[c]) : "–") << " |";
        md << "\n";
      }
      md << "\n";
    }
  }
  // Every other top-level key: a key/value table.
  for (auto& [key, v] : report.items()) {
    if (key == "sequences" || key == "overall") continue;
    std::map<std::string, nlohmann::json> flat;
    if (v.is_object())
      flatten(v, "", flat, 3);
    else
      flat[key] = v;
    md << "## " << key << "\n\n| key | value |\n|---|---|\n";
    for (auto& [k, val] : flat) md << "| " << k << " | " << cell(val) << " |\n";
    md << "\n";
  }
  return md.str();
}

}  // namespace slamaware
