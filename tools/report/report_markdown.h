#pragma once
#include <nlohmann/json.hpp>
#include <string>

namespace slamaware {

/// report.md of an eval or bench report: one table per section, sequences as rows.
std::string renderMarkdown(const nlohmann::json& report);

}  // namespace slamaware
