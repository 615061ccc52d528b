// slamaware-annotate: turns a recorded session into pictures a person can check at a glance:
//   annotated.mp4  every CAMERA frame with its objects as the object map labelled them at that
//                  frame (OBJECT_DETECTIONS: each object's one box, its fused label and posterior;
//                  background candidates left out, or faint with --background), the SLAM state of
//                  the frame; --single-view draws every box with the recognizer's own label instead
//                  (DETECTIONS), as a recording without OBJECT_DETECTIONS is drawn;
//   topdown.png    the semi-dense map seen from above its dominant plane, the camera path and
//                  the labelled objects of the last OBJECT_MAP (not background), their labels
//                  placed where they do not cover each other.
// It reads only the log (no bus), so it works on any recording, live or replayed.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <Eigen/Dense>
#include <filesystem>
#include <map>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <optional>

#include "common/bus/image_msg.h"
#include "common/bus/log_reader.h"
#include "common/bus/node.h"
#include "common/bus/object_detections_msg.h"
#include "common/image_codec.h"
#include "slamaware/detections_t.hpp"
#include "slamaware/object_detections_t.hpp"
#include "slamaware/object_map_t.hpp"
#include "slamaware/point_cloud_t.hpp"
#include "slamaware/pose_t.hpp"
#include "slamaware/proposals_t.hpp"

using namespace slamaware;
namespace fs = std::filesystem;

namespace {

template <class T>
std::optional<T> decodeAs(const LogRecord& ev) {
  T msg{};
  if (!decodeRecord(ev, &msg)) return std::nullopt;
  return msg;
}

const char* stateName(int s) {
  switch (s) {
    case pose_t::STATE_INITIALIZING:
      return "INITIALIZING";
    case pose_t::STATE_TRACKING:
      return "TRACKING";
    case pose_t::STATE_LOST:
      return "LOST";
    case pose_t::STATE_RELOCALIZED:
      return "RELOCALIZED";
  }
  return "?";
}

// A colour per label, the same in every picture.
cv::Scalar labelColour(const std::string& label) {
  if (label == "background" || label.empty()) return {160, 160, 160};
  const size_t h = std::hash<std::string>{}(label);
  cv::Mat hsv(1, 1, CV_8UC3, cv::Scalar(static_cast<double>(h % 180), 200, 255)), bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
  const auto c = bgr.at<cv::Vec3b>(0, 0);
  return {static_cast<double>(c[0]), static_cast<double>(c[1]), static_cast<double>(c[2])};
}

// The rectangle a label's text takes with its baseline-left corner at `at`.
cv::Rect labelRect(const std::string& text, cv::Point at) {
  int base = 0;
  const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, &base);
  return {at.x, at.y - size.height - 2, size.width + 2, size.height + 2 + base};
}

// Draws a label (text on its colour) with its baseline-left corner at `at`, kept inside the image.
cv::Rect putLabel(cv::Mat& img, const std::string& text, cv::Point at, const cv::Scalar& colour) {
  cv::Rect r = labelRect(text, at);
  r.x = std::clamp(r.x, 0, std::max(0, img.cols - r.width));
  r.y = std::clamp(r.y, 0, std::max(0, img.rows - r.height));
  cv::rectangle(img, r, colour, cv::FILLED);
  cv::putText(img, text, {r.x + 1, r.y + r.height - 4}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0},
              1, cv::LINE_AA);
  return r;
}

// A place for a label of an object drawn at `box` that covers none of `taken`: above the box, below
// it, then further out in steps; the first free one (else above the box). The place is added to
// `taken`.
cv::Point freeLabelPlace(const std::string& text, const cv::Rect& box,
                         std::vector<cv::Rect>* taken) {
  const cv::Rect size = labelRect(text, {0, 0});
  std::vector<cv::Point> candidates;
  for (int step = 0; step < 12; ++step) {
    const int d = step * (size.height + 2);
    candidates.push_back({box.x, box.y - 2 - d});
    candidates.push_back({box.x, box.y + box.height + size.height + d});
    candidates.push_back({box.x + box.width + 4, box.y + size.height + d});
  }
  for (const cv::Point& c : candidates) {
    const cv::Rect r = labelRect(text, c);
    if (std::none_of(taken->begin(), taken->end(),
                     [&](const cv::Rect& t) { return (t & r).area() > 0; })) {
      taken->push_back(r);
      return c;
    }
  }
  taken->push_back(labelRect(text, candidates.front()));
  return candidates.front();
}

struct FrameAnnotations {
  std::optional<pose_t> pose;
  std::optional<proposals_t> proposals;
  std::optional<detections_t> detections;
  std::optional<object_detections_t> objects;
};

struct DrawOptions {
  bool single_view = false;  ///< the recognizer's labels of every box instead of the map's
  bool background = false;   ///< also the background candidates and the objects' other boxes, faint
  /// Objects a user labelled (slamaware-ctl label), by id, as the session's last OBJECT_MAP has
  /// them.
  std::map<int32_t, std::string> user_labels;
};

struct Session {
  std::map<int32_t, FrameAnnotations> by_seq;
  std::optional<object_map_t> last_objects;
  // The map of the last map id: points per keyframe (a full cloud replaces them all).
  int32_t map_id = -1;
  std::map<int32_t, std::vector<cv::Point3f>> points;
  std::map<int32_t, std::vector<cv::Vec3b>> colours;
  std::vector<cv::Point3f> path;
  int64_t frames = 0, undecodable = 0;
};

void addCloud(Session& s, const point_cloud_t& c) {
  if (c.map_id != s.map_id) {
    s.map_id = c.map_id;
    s.points.clear();
    s.colours.clear();
    s.path.clear();
  }
  if (c.full) {
    s.points.clear();
    s.colours.clear();
  } else {
    s.points.erase(c.keyframe_id);
    s.colours.erase(c.keyframe_id);
  }
  for (int i = 0; i < c.num_points; ++i) {
    const int32_t kf = c.full ? c.keyframe_ids[static_cast<size_t>(i)] : c.keyframe_id;
    const size_t k = static_cast<size_t>(i);
    if (!std::isfinite(c.x[k]) || !std::isfinite(c.y[k]) || !std::isfinite(c.z[k])) continue;
    s.points[kf].emplace_back(c.x[k], c.y[k], c.z[k]);
    s.colours[kf].emplace_back(static_cast<uint8_t>(c.b[k]), static_cast<uint8_t>(c.g[k]),
                               static_cast<uint8_t>(c.r[k]));
  }
}

Session readSession(const std::string& log, const Channels& ch) {
  Session s;
  LogReader reader(log);
  try {
    while (auto ev = reader.next()) {
      bool ok = true;
      if (ev->channel == ch.slam_pose) {
        if (auto m = decodeAs<pose_t>(*ev)) {
          s.by_seq[m->seq].pose = *m;
          if ((m->state == pose_t::STATE_TRACKING || m->state == pose_t::STATE_RELOCALIZED) &&
              m->map_id == s.map_id)
            s.path.emplace_back(static_cast<float>(m->position[0]),
                                static_cast<float>(m->position[1]),
                                static_cast<float>(m->position[2]));
        } else {
          ok = false;
        }
      } else if (ev->channel == ch.proposals) {
        auto m = decodeAs<proposals_t>(*ev);
        ok = m.has_value();
        if (m) s.by_seq[m->seq].proposals = *m;
      } else if (ev->channel == ch.detections) {
        auto m = decodeAs<detections_t>(*ev);
        ok = m.has_value();
        if (m) s.by_seq[m->seq].detections = *m;
      } else if (ev->channel == ch.object_detections) {
        auto m = decodeAs<object_detections_t>(*ev);
        ok = m.has_value();
        if (m) s.by_seq[m->seq].objects = *m;
      } else if (ev->channel == ch.object_map) {
        auto m = decodeAs<object_map_t>(*ev);
        ok = m.has_value();
        if (m) s.last_objects = *m;
      } else if (ev->channel == ch.slam_map) {
        auto m = decodeAs<point_cloud_t>(*ev);
        ok = m.has_value();
        if (m) addCloud(s, *m);
      } else if (ev->channel == ch.camera) {
        ++s.frames;
      }
      if (!ok) ++s.undecodable;
    }
  } catch (const LogError& e) {
    spdlog::warn("{} (annotating what comes before it)", e.what());
  }
  return s;
}

// The frame's objects as the map labelled them then: each object's box with its label and
// posterior; the rest faint (options.background) or left out. Returns the boxes drawn.
int drawObjects(cv::Mat& img, const object_detections_t& d, const DrawOptions& options) {
  int drawn = 0;
  std::vector<cv::Rect> taken;
  for (int i = 0; i < d.num_boxes; ++i) {
    const size_t k = static_cast<size_t>(i);
    const bool object = isLabelledObject(d, k);
    if (!object && !options.background) continue;
    const box_t& b = d.boxes[k];
    const cv::Rect r(cvRound(b.x), cvRound(b.y), cvRound(b.w), cvRound(b.h));
    if (!object) {
      cv::rectangle(img, r, {150, 150, 150}, 1);
      ++drawn;
      continue;
    }
    const cv::Scalar colour = labelColour(d.labels[k]);
    cv::rectangle(img, r, colour, 2);
    std::string text = objectLabelText(d, k);
    if (k < d.object_ids.size()) {
      auto user = options.user_labels.find(d.object_ids[k]);
      if (user != options.user_labels.end()) text = "[" + user->second + "] " + text;
    }
    putLabel(img, text, freeLabelPlace(text, r, &taken), colour);
    ++drawn;
  }
  return drawn;
}

void drawFrame(cv::Mat& img, int32_t seq, const FrameAnnotations& a, const DrawOptions& options) {
  std::string state = "no pose";
  if (a.pose)
    state = std::string(stateName(a.pose->state)) + " map " + std::to_string(a.pose->map_id);
  int boxes = 0;
  const char* what = "boxes";
  if (a.objects && !options.single_view) {
    boxes = drawObjects(img, *a.objects, options);
    what = options.background ? "boxes" : "objects";
  } else if (a.detections) {
    const detections_t& d = *a.detections;
    for (int i = 0; i < d.num_boxes; ++i) {
      const auto& lp = d.log_prob[static_cast<size_t>(i)];
      const int best = static_cast<int>(std::max_element(lp.begin(), lp.end()) - lp.begin());
      const std::string& label = d.class_names[static_cast<size_t>(best)];
      const box_t& b = d.boxes[static_cast<size_t>(i)];
      const cv::Scalar colour = labelColour(label);
      cv::rectangle(img, cv::Rect(cvRound(b.x), cvRound(b.y), cvRound(b.w), cvRound(b.h)), colour,
                    label == "background" ? 1 : 2);
      char text[96];
      std::snprintf(text, sizeof(text), "#%d %s %.2f", d.candidate_ids[static_cast<size_t>(i)],
                    label.c_str(), std::exp(lp[static_cast<size_t>(best)]));
      putLabel(img, text, {cvRound(b.x), cvRound(b.y)}, colour);
      ++boxes;
    }
  } else if (a.proposals) {
    const proposals_t& p = *a.proposals;
    for (int i = 0; i < p.num_boxes; ++i) {
      const box_t& b = p.boxes[static_cast<size_t>(i)];
      cv::rectangle(img, cv::Rect(cvRound(b.x), cvRound(b.y), cvRound(b.w), cvRound(b.h)),
                    {255, 255, 255}, 1);
      putLabel(img, "#" + std::to_string(p.candidate_ids[static_cast<size_t>(i)]),
               {cvRound(b.x), cvRound(b.y)}, {255, 255, 255});
      ++boxes;
    }
  }
  char text[128];
  std::snprintf(text, sizeof(text), "frame %d  SLAM %s  %s %d", seq, state.c_str(), what, boxes);
  cv::rectangle(img, {0, img.rows - 22}, {img.cols, img.rows}, {0, 0, 0}, cv::FILLED);
  cv::putText(img, text, {6, img.rows - 7}, cv::FONT_HERSHEY_SIMPLEX, 0.5, {255, 255, 255}, 1,
              cv::LINE_AA);
}

// The map from above: the plane spanned by the two main directions of the points.
bool drawTopDown(const Session& s, const std::string& path) {
  std::vector<Eigen::Vector3d> pts;
  std::vector<cv::Vec3b> cols;
  for (const auto& [kf, p] : s.points)
    for (size_t i = 0; i < p.size(); ++i) {
      pts.emplace_back(p[i].x, p[i].y, p[i].z);
      cols.push_back(s.colours.at(kf)[i]);
    }
  if (pts.size() < 10) return false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= static_cast<double>(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) cov += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d u = eig.eigenvectors().col(2), v = eig.eigenvectors().col(1);
  auto plane = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector2d((p - mean).dot(u), (p - mean).dot(v));
  };
  // Extent: the 1st..99th percentile of the points, plus the camera path.
  std::vector<double> us, vs;
  for (const auto& p : pts) {
    const auto q = plane(p);
    us.push_back(q.x());
    vs.push_back(q.y());
  }
  auto pct = [](std::vector<double> x, double f) {
    std::nth_element(x.begin(), x.begin() + static_cast<long>(f * (x.size() - 1)), x.end());
    return x[static_cast<size_t>(f * (x.size() - 1))];
  };
  double u0 = pct(us, 0.01), u1 = pct(us, 0.99), v0 = pct(vs, 0.01), v1 = pct(vs, 0.99);
  for (const auto& c : s.path) {
    const auto q = plane(Eigen::Vector3d(c.x, c.y, c.z));
    u0 = std::min(u0, q.x());
    u1 = std::max(u1, q.x());
    v0 = std::min(v0, q.y());
    v1 = std::max(v1, q.y());
  }
  const int size = 800, margin = 40;
  const double scale = (size - 2 * margin) / std::max({u1 - u0, v1 - v0, 1e-6});
  cv::Mat img(size, size, CV_8UC3, cv::Scalar(255, 255, 255));
  auto px = [&](const Eigen::Vector3d& p) {
    const auto q = plane(p);
    return cv::Point(cvRound(margin + (q.x() - u0) * scale),
                     cvRound(size - margin - (q.y() - v0) * scale));
  };
  for (size_t i = 0; i < pts.size(); ++i) {
    const cv::Point q = px(pts[i]);
    if (q.x >= 0 && q.y >= 0 && q.x < size && q.y < size) img.at<cv::Vec3b>(q) = cols[i];
  }
  for (size_t i = 1; i < s.path.size(); ++i)
    cv::line(img, px({s.path[i - 1].x, s.path[i - 1].y, s.path[i - 1].z}),
             px({s.path[i].x, s.path[i].y, s.path[i].z}), {200, 90, 0}, 2, cv::LINE_AA);
  std::vector<cv::Rect> taken;
  if (s.last_objects) {
    for (const auto& o : s.last_objects->objects) {
      // The labelled objects only: background candidates (most of them) would hide the map.
      if (o.map_id != s.map_id ||
          ((o.label == "background" || o.label.empty()) && o.user_label.empty()))
        continue;
      // An object with evidence but no position yet (NaN centroid, object_t.lcm): not drawn.
      bool placed = true;
      for (int k = 0; k < 3; ++k)
        placed = placed && std::isfinite(o.centroid[k]) && std::isfinite(o.extent[k]);
      if (!placed) continue;
      const Eigen::Vector3d c(o.centroid[0], o.centroid[1], o.centroid[2]);
      const Eigen::Vector3d half(o.extent[0] / 2, o.extent[1] / 2, o.extent[2] / 2);
      cv::Point lo(size, size), hi(0, 0);
      for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3d corner =
            c + Eigen::Vector3d((k & 1 ? 1 : -1) * half.x(), (k & 2 ? 1 : -1) * half.y(),
                                (k & 4 ? 1 : -1) * half.z());
        const cv::Point q = px(corner);
        lo = {std::min(lo.x, q.x), std::min(lo.y, q.y)};
        hi = {std::max(hi.x, q.x), std::max(hi.y, q.y)};
      }
      const cv::Scalar colour = labelColour(o.label);
      const cv::Rect box(lo, hi);
      cv::rectangle(img, box, colour, 2);
      const std::string text = "#" + std::to_string(o.id) + " " +
                               (o.user_label.empty() ? "" : "[" + o.user_label + "] ") + o.label +
                               " (" + std::to_string(o.num_views) + " views)";
      const cv::Point at = freeLabelPlace(text, box, &taken);
      const cv::Rect label = putLabel(img, text, at, colour);
      // A label moved away from its box gets a line to it.
      const cv::Rect next_to(box.x - 4, box.y - label.height - 4, box.width + label.width + 8,
                             box.height + 2 * label.height + 8);
      if ((label & next_to).area() == 0)
        cv::line(img, {label.x, label.y + label.height / 2}, {box.x, box.y}, colour, 1,
                 cv::LINE_AA);
    }
  }
  cv::putText(img,
              "map " + std::to_string(s.map_id) + ": " + std::to_string(pts.size()) +
                  " points, camera path in blue",
              {10, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 0}, 1, cv::LINE_AA);
  writeImage(path, img);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-annotate: annotated video and top-down map picture of a recorded session"};
  NodeArgs node;
  std::string log, out_dir = "build/demo";
  double fps = 30;
  DrawOptions draw;
  addNodeOptions(app, node, false);
  app.add_flag(
      "--single-view", draw.single_view,
      "draw every box with the recognizer's own label (DETECTIONS) instead of the object map's");
  app.add_flag("--background", draw.background,
               "also draw the background candidates and the objects' other boxes (faint)");
  app.add_option("log", log, "LCM log of a session (lcm-logger format)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--out-dir", out_dir, "folder for annotated.mp4 and topdown.png");
  app.add_option("--fps", fps, "frame rate of the video")->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);
  return runNode("annotate", node, [&]() -> int {
    const SystemConfig sys = loadSystem(node);
    const Channels& ch = sys.channels;
    fs::create_directories(out_dir);
    const Session s = readSession(log, ch);
    if (s.undecodable) spdlog::warn("{} undecodable messages skipped", s.undecodable);
    if (s.last_objects)
      for (const auto& o : s.last_objects->objects)
        if (!o.user_label.empty()) draw.user_labels[o.id] = o.user_label;

    const std::string video = out_dir + "/annotated.mp4";
    cv::VideoWriter writer;
    int64_t written = 0;
    LogReader reader(log);
    try {
      while (auto ev = reader.next()) {
        if (ev->channel != ch.camera) continue;
        auto msg = decodeAs<image_t>(*ev);
        if (!msg) continue;
        cv::Mat img;
        try {
          img = decodeImageMessage(*msg, "CAMERA frame " + std::to_string(msg->seq));
        } catch (const std::exception& e) {
          spdlog::warn("{}", e.what());
          continue;
        }
        if (!writer.isOpened()) {
          if (!writer.open(video, cv::CAP_FFMPEG, cv::VideoWriter::fourcc('m', 'p', '4', 'v'), fps,
                           img.size())) {
            spdlog::error("{}: cannot open a video writer (OpenCV without FFmpeg?)", video);
            return 1;
          }
        }
        auto it = s.by_seq.find(msg->seq);
        drawFrame(img, msg->seq, it == s.by_seq.end() ? FrameAnnotations{} : it->second, draw);
        writer.write(img);
        ++written;
      }
    } catch (const LogError&) {
      // reported by readSession
    }
    writer.release();
    spdlog::info("{}: {} frames", video, written);
    const std::string top = out_dir + "/topdown.png";
    if (drawTopDown(s, top))
      spdlog::info("{}: map {} with {} objects", top, s.map_id,
                   s.last_objects ? s.last_objects->num_objects : 0);
    else
      spdlog::warn("no map in {}: no top-down picture", log);
    return written > 0 ? 0 : 1;
  });
}
