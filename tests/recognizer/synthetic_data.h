#pragma once
// Small synthetic inputs for the recognizer tests: an object set of two categories that differ in
// shape and colour ("disc": round blobs; "bar": stripes), each with a few instances (hue and
// scale vary per instance, pose and noise per view), and a scene sequence of cluttered frames
// with one object each and its ground-truth box (boxes.csv), for background examples.
#include <opencv2/core/mat.hpp>
#include <string>

namespace slamaware::test {

/// One view of an instance of "disc" or "bar" on its own background, size x size px, 8-bit BGR.
cv::Mat syntheticObjectView(const std::string& category, int instance, int view, int size);

/// Writes <dir>/<category>/<category>_<i>/<category>_<i>_1_<v>_crop.png for both categories,
/// `instances` instances each and `views` views per instance; returns dir.
std::string makeSyntheticObjectSet(const std::string& dir, int instances, int views, int size = 72);

/// Writes a sequence folder of `frames` 320x240 cluttered frames, each with one object pasted at
/// a known place (boxes.csv); returns dir.
std::string makeSyntheticScenes(const std::string& dir, int frames);

/// A textured frame (colour gradients, rectangles, lines and noise) for encoder tests.
cv::Mat texturedFrame(int seed, int width = 640, int height = 480);

}  // namespace slamaware::test
