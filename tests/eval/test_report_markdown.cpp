// report.md: the recognition table in the paper's style (per class AP / precision / recall, single
// view against multi-view online and final, the mAP rows and the paper's mAPs), the per-sequence
// rows, the photographed frames' table, the plot, and the runtime table of the bench when its keys
// are there.
#include <gtest/gtest.h>

#include "tools/report/report_markdown.h"

using namespace slamaware;

namespace {

nlohmann::json section(double map, double ap_cap, double precision, double recall) {
  return nlohmann::json::parse(
      R"({"mAP": )" + std::to_string(map) + R"(, "recall": )" + std::to_string(recall) +
      R"(, "ground_truth_boxes": 70, "boxes": 400, "plot": "build/eval/plots/suite_pr.png",
      "per_class": {"cap": {"AP": )" +
      std::to_string(ap_cap) + R"(, "precision": )" + std::to_string(precision) +
      R"(, "recall": )" + std::to_string(recall) + R"(, "ground_truth_boxes": 70},
                    "bowl": {"AP": null, "precision": null, "recall": null, "ground_truth_boxes": 0}},
      "diagnostics": {"accuracy_on_objects": 70.5}})");
}

}  // namespace

TEST(ReportMarkdown, RecognitionTableInThePapersStyleWithItsMaps) {
  nlohmann::json r;
  r["overall"]["single_view"] = section(66.5, 66.5, 70.9, 87.1);
  r["overall"]["multi_view_online"] = section(60.2, 60.2, 66.0, 86.0);
  r["overall"]["multi_view_final"] = section(56.1, 56.1, 64.5, 85.7);
  for (const char* view :
       {"single_view", "multi_view_online", "multi_view_final"}) {  // the same boxes
    r["overall"][view]["per_class"]["cap"]["boxed"] = 91.4;
    r["overall"][view]["boxed"] = 91.4;
    r["overall"][view]["mAP_bound"] = 91.4;
  }
  r["overall"]["slam"]["tracked_pct"] = 99.5;
  r["sequences"]["cafe_small"]["single_view"] = section(66.5, 66.5, 70.9, 87.1);
  r["sequences"]["cafe_small"]["multi_view_online"] = section(60.2, 60.2, 66.0, 86.0);
  r["sequences"]["cafe_small"]["multi_view_final"] = section(56.1, 56.1, 64.5, 85.7);
  r["sequences"]["cafe_small"]["multi_view_final"]["objects"] = 38;
  r["sequences"]["cafe_small"]["slam"]["tracked_pct"] = 99.5;
  r["sequences"]["uw_scenes_v2_public"]["gt_boxes"] = nlohmann::json::parse(
      R"({"boxes": 34, "accuracy": 41.2, "per_class": {"bowl": {"boxes": 10, "accuracy": 20.0}}})");
  r["sequences"]["uw_scenes_v2_public"]["single_view_ss"] = section(30.5, 30.5, 40.0, 50.0);
  const std::string md = renderMarkdown(r);
  EXPECT_NE(
      md.find(
          "| cap | 70 | 66.5 | 60.2 | 56.1 | 70.9 | 66.0 | 64.5 | 87.1 | 86.0 | 85.7 | 91.4 |\n"),
      std::string::npos)
      << md;
  EXPECT_NE(md.find("| bowl | 0 | – | – | – | – | – | – | – | – | – | – |\n"), std::string::npos)
      << md;
  EXPECT_NE(md.find("| bound: mean boxed share, no labelling of these boxes does better | | 91.4 | "
                    "91.4 | 91.4 |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("**66.5** | **60.2** | **56.1**"), std::string::npos) << md;
  EXPECT_NE(
      md.find("Pillai & Leonard 2015, UW RGB-D Scenes v2 (their numbers), mAP | | 81.5 | | 89.8 |"),
      std::string::npos)
      << md;
  EXPECT_NE(md.find("![precision-recall per class, synthetic suite](plots/suite_pr.png)"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| cafe_small | 70 | 400 | 66.5 | 60.2 | 56.1 | 87.1 | 86.0 | 85.7 | 38 |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| uw_scenes_v2_public | 34 | 41.2 | bowl 20.0 (10) | 30.5 | 50.0 |"),
            std::string::npos)
      << md;
  // The sections with their own tables are not repeated in the generic ones; the others still are.
  EXPECT_EQ(md.find("## single_view"), std::string::npos);
  EXPECT_EQ(md.find("## multi_view"), std::string::npos);
  EXPECT_NE(md.find("## slam"), std::string::npos);
  EXPECT_EQ(md.find("number of classes"), std::string::npos) << "no bench keys, no runtime table";
}

TEST(ReportMarkdown, RuntimeAgainstTheNumberOfClassesWhenTheBenchHasIt) {
  nlohmann::json r;
  r["recognizer_ms_per_frame"] = 80.0;
  r["recognizer_ms_per_frame_51_classes"] = 84.0;
  r["classes_runtime_ratio_51_vs_5"] = 1.05;
  r["recognizer_ms_per_frame_12_boxes"] = 21.3;
  const std::string md = renderMarkdown(r);
  EXPECT_NE(md.find("| 5 | 80.0 | 1.00 |"), std::string::npos) << md;
  EXPECT_NE(
      md.find(
          "about as many as a frame publishes (features only where a box is): 21.3 ms per frame"),
      std::string::npos)
      << md;
  EXPECT_NE(md.find("| 51 | 84.0 | 1.05 |"), std::string::npos) << md;
  EXPECT_EQ(md.find("Recognition: single view"), std::string::npos)
      << "no recognition in a bench report";
}
