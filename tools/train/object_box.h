#pragma once
// Where the object is in a photographed crop that has no mask. Training boxes must frame the object
// as a proposal does: a loose crop (UMD bowls and mugs: the object is 12-50 % of it, the rest a
// blue cloth) boxed whole teaches "a blue cloth" as the object's look.
#include <opencv2/core.hpp>

namespace slamaware::recognizer {

/// The object's box in `crop` (8-bit BGR), by GrabCut (OpenCV) with a border band of 6 % of the
/// shorter side as background and the rest as probable foreground. A foreground that reaches the
/// band on any side touches the crop's border there (the band hid that part from the cut): the
/// crop is framed by its object and the whole crop is returned. So a tight crop keeps its whole
/// extent, a loose one is boxed around its object. No foreground, or a crop smaller than 16 px:
/// the whole crop. Deterministic (OpenCV's RNG is reseeded).
cv::Rect objectBoxInCrop(const cv::Mat& crop);

}  // namespace slamaware::recognizer
