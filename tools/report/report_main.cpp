// slamaware-report: assembles the machine-read reports of `make eval` and `make bench` from the
// JSON fragments that each part writes (docs/architecture.md §7), and renders report.md.
#include <CLI/CLI.hpp>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "tools/report/report_markdown.h"

using nlohmann::json;

namespace {

// Objects merge key by key; anything else in `b` replaces what `a` had.
void deepMerge(json& a, const json& b) {
  if (!a.is_object() || !b.is_object()) {
    a = b;
    return;
  }
  for (auto it = b.begin(); it != b.end(); ++it) deepMerge(a[it.key()], it.value());
}

json readJson(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  try {
    return json::parse(in);
  } catch (const json::parse_error& e) {
    throw std::runtime_error(path + ": not valid JSON: " + e.what());
  }
}

void writeFile(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    out << text;
    if (!out) throw std::runtime_error(path + ": cannot write");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
    throw std::runtime_error(path + ": cannot rename");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"slamaware-report: merge report fragments and render report.md"};
  app.require_subcommand(1);
  std::vector<std::string> inputs;
  std::string out, md;
  auto* merge = app.add_subcommand("merge", "deep-merge JSON fragments into one report");
  merge->add_option("inputs", inputs, "fragment files (later ones win on conflicts)")->required();
  merge->add_option("--out", out, "report.json to write")->required();
  merge->add_option("--markdown", md, "also render this report.md");
  CLI11_PARSE(app, argc, argv);
  try {
    json report = json::object();
    for (const auto& f : inputs) deepMerge(report, readJson(f));
    writeFile(out, report.dump(2) + "\n");
    if (!md.empty()) writeFile(md, slamaware::renderMarkdown(report));
  } catch (const std::exception& e) {
    std::cerr << "slamaware-report: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
