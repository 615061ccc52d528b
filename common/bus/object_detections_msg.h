#pragma once
// OBJECT_DETECTIONS as a user reads it (slamaware-annotate, slamaware-ctl watch): the boxes that
// stand for an object the map calls one of the model's classes, and their one-line label.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "slamaware/object_detections_t.hpp"

namespace slamaware {

/// Box i is its object's one box in the frame (PRIMARY) and the object is labelled with a class
/// that is not background.
inline bool isLabelledObject(const object_detections_t& d, size_t i) {
  return i < d.roles.size() && i < d.labels.size() && d.roles[i] == object_detections_t::PRIMARY &&
         !d.labels[i].empty() && d.labels[i] != "background";
}

/// "#<object id> <label> <posterior of the label>" for box i.
inline std::string objectLabelText(const object_detections_t& d, size_t i) {
  const size_t c = static_cast<size_t>(
      std::find(d.class_names.begin(), d.class_names.end(), d.labels[i]) - d.class_names.begin());
  const double p = c < d.log_posterior[i].size() ? std::exp(d.log_posterior[i][c]) : 0.0;
  char text[96];
  std::snprintf(text, sizeof(text), "#%d %s %.2f", d.object_ids[i], d.labels[i].c_str(), p);
  return text;
}

}  // namespace slamaware
