// Image codecs: round trips, and corrupt data refused with a message.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/bus/image_msg.h"
#include "common/image_codec.h"

using namespace slamaware;

namespace {
cv::Mat testImage() {
  cv::Mat img(120, 160, CV_8UC3);
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c) img.at<cv::Vec3b>(r, c) = cv::Vec3b(r * 2, c, (r + c) % 256);
  return img;
}
}  // namespace

TEST(ImageCodec, PngIsLossless) {
  const cv::Mat img = testImage();
  const auto png = encodePng(img);
  const cv::Mat back = decodeImage(png.data(), png.size(), "test");
  EXPECT_EQ(cv::norm(img, back, cv::NORM_INF), 0);
}

TEST(ImageCodec, Png16BitDepth) {
  cv::Mat depth(10, 10, CV_16UC1);
  for (int i = 0; i < 100; ++i) depth.at<uint16_t>(i / 10, i % 10) = static_cast<uint16_t>(i * 600);
  const auto png = encodePng(depth);
  const cv::Mat back = cv::imdecode(png, cv::IMREAD_UNCHANGED);
  EXPECT_EQ(back.type(), CV_16UC1);
  EXPECT_EQ(cv::norm(depth, back, cv::NORM_INF), 0);
}

// The codec is libjpeg and libpng with the settings OpenCV's imgcodecs uses (which the processes no
// longer load): the same JPEG bytes, the same decoded pixels, the same PNG bytes at a given
// compression, as OpenCV gives on this machine. Recordings made before stay byte-identical.
TEST(ImageCodec, SameBytesAndPixelsAsOpenCv) {
  cv::Mat noisy(97, 131, CV_8UC3);
  cv::RNG(7).fill(noisy, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(noisy, noisy, cv::Size(5, 5), 1.5);
  noisy += testImage()(cv::Rect(0, 0, 131, 97)) * 0.5;
  cv::Mat grey;
  cv::cvtColor(noisy, grey, cv::COLOR_BGR2GRAY);
  cv::Mat bgra;
  cv::cvtColor(noisy, bgra, cv::COLOR_BGR2BGRA);
  cv::Mat depth(40, 50, CV_16UC1);
  cv::RNG(8).fill(depth, cv::RNG::UNIFORM, 0, 65536);
  auto same = [](const cv::Mat& a, const cv::Mat& b) {
    return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
  };
  for (const cv::Mat* img : {&noisy, &grey}) {
    for (int q : {30, 90, 95}) {
      SCOPED_TRACE("JPEG quality " + std::to_string(q) + ", channels " +
                   std::to_string(img->channels()));
      std::vector<uint8_t> theirs;
      ASSERT_TRUE(cv::imencode(".jpg", *img, theirs, {cv::IMWRITE_JPEG_QUALITY, q}));
      const std::vector<uint8_t> ours = encodeJpeg(*img, q);
      EXPECT_EQ(ours, theirs);
      for (bool as_grey : {false, true})
        EXPECT_TRUE(same(decodeImage(ours.data(), ours.size(), "jpeg", as_grey),
                         cv::imdecode(theirs, as_grey ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR)));
    }
  }
  for (const cv::Mat* img : {&noisy, &grey, &bgra, &depth}) {
    SCOPED_TRACE("PNG of type " + std::to_string(img->type()));
    std::vector<uint8_t> theirs;
    ASSERT_TRUE(cv::imencode(".png", *img, theirs, {cv::IMWRITE_PNG_COMPRESSION, 6}));
    EXPECT_EQ(encodePng(*img, 6), theirs);
    for (bool as_grey : {false, true})
      EXPECT_TRUE(same(decodeImage(theirs.data(), theirs.size(), "png", as_grey),
                       cv::imdecode(theirs, as_grey ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR)));
    const std::string path = ::testing::TempDir() + "/codec_unchanged.png";
    writeImage(path, *img);
    EXPECT_TRUE(same(readImageUnchanged(path), cv::imread(path, cv::IMREAD_UNCHANGED)));
    EXPECT_TRUE(same(readImageUnchanged(path), *img));
  }
}

TEST(ImageCodec, JpegQualityAffectsErrorAndSize) {
  const cv::Mat img = testImage();
  const auto q95 = encodeJpeg(img, 95), q30 = encodeJpeg(img, 30);
  EXPECT_GT(q95.size(), q30.size());
  const double e95 =
      cv::norm(img, decodeImage(q95.data(), q95.size(), "q95"), cv::NORM_L1) / img.total();
  const double e30 =
      cv::norm(img, decodeImage(q30.data(), q30.size(), "q30"), cv::NORM_L1) / img.total();
  EXPECT_LT(e95, e30);
  EXPECT_LT(e95, 6.0);
}

TEST(ImageCodec, CorruptDataIsRefused) {
  const auto jpeg = encodeJpeg(testImage(), 90);
  auto errorOf = [](const std::vector<uint8_t>& d) -> std::string {
    try {
      decodeImage(d.data(), d.size(), "CAMERA seq 7");
    } catch (const ImageError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(errorOf({}).find("empty"), std::string::npos);
  EXPECT_NE(errorOf({1, 2, 3, 4, 5}).find("not a JPEG or PNG"), std::string::npos);
  std::vector<uint8_t> truncated(jpeg.begin(), jpeg.begin() + jpeg.size() / 2);
  EXPECT_NE(errorOf(truncated).find("truncated JPEG"), std::string::npos);
  EXPECT_NE(errorOf(truncated).find("CAMERA seq 7"), std::string::npos) << "names the source";
  auto png = encodePng(testImage());
  png.resize(png.size() - 20);
  EXPECT_NE(errorOf(png).find("truncated PNG"), std::string::npos);
}

// A header asking for more pixels than any camera gives is refused before the decoder allocates
// for it (OpenCV would try up to a gigapixel: 3 GB from a 60-byte file).
TEST(ImageCodec, AHeaderAskingForAGiantImageIsRefusedBeforeDecoding) {
  auto errorOf = [](const std::vector<uint8_t>& d) -> std::string {
    try {
      decodeImage(d.data(), d.size(), "frame.png");
    } catch (const ImageError& e) {
      return e.what();
    }
    return "";
  };
  auto png = encodePng(testImage());
  int w = 0, h = 0;
  ASSERT_TRUE(peekImageSize(png.data(), png.size(), &w, &h));
  EXPECT_EQ(w, testImage().cols);
  EXPECT_EQ(h, testImage().rows);
  for (int i = 16; i < 24; ++i) png[i] = 0;
  png[17] = png[21] = 0x01;  // 65536 x 65536
  const std::string png_error = errorOf(png);
  EXPECT_NE(png_error.find("65536x65536"), std::string::npos) << png_error;
  EXPECT_NE(png_error.find("frame.png"), std::string::npos) << png_error;
  auto jpeg = encodeJpeg(testImage(), 90);
  ASSERT_TRUE(peekImageSize(jpeg.data(), jpeg.size(), &w, &h));
  EXPECT_EQ(w, testImage().cols);
  size_t sof = 2;
  while (!(jpeg[sof] == 0xFF && jpeg[sof + 1] == 0xC0))
    sof += 2 + (jpeg[sof + 2] << 8 | jpeg[sof + 3]);
  jpeg[sof + 5] = jpeg[sof + 6] = jpeg[sof + 7] = jpeg[sof + 8] = 0xEA;  // 60138 x 60138
  EXPECT_NE(errorOf(jpeg).find("60138x60138"), std::string::npos) << errorOf(jpeg);
}

TEST(ImageCodec, MissingFileNamed) {
  try {
    readImage("/nonexistent/frame.png");
    FAIL();
  } catch (const ImageError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/frame.png"), std::string::npos);
  }
}

TEST(ImageMessage, RoundTripsEveryFormat) {
  const cv::Mat img = testImage();
  const image_t raw = makeImageMessage(img, 5, 6, image_t::PIXEL_FORMAT_RGB8);
  EXPECT_EQ(raw.size, 160 * 120 * 3);
  EXPECT_EQ(raw.data[0], img.at<cv::Vec3b>(0, 0)[2]) << "RGB8 is r, g, b";
  EXPECT_EQ(cv::norm(img, decodeImageMessage(raw, "raw"), cv::NORM_INF), 0);
  const image_t grey = makeImageMessage(img, 5, 6, image_t::PIXEL_FORMAT_GRAY8);
  EXPECT_EQ(grey.size, 160 * 120);
  EXPECT_EQ(decodeImageMessage(grey, "grey", true).channels(), 1);
  const image_t jpeg = makeImageMessage(img, 5, 6, image_t::PIXEL_FORMAT_JPEG, 95);
  EXPECT_LT(cv::norm(img, decodeImageMessage(jpeg, "jpeg"), cv::NORM_L1) / img.total(), 6.0);
}

TEST(ImageMessage, InconsistentMessagesAreRefused) {
  image_t m = makeImageMessage(testImage(), 5, 6, image_t::PIXEL_FORMAT_RGB8);
  m.width = 161;
  EXPECT_THROW(decodeImageMessage(m, "x"), ImageError);
  image_t j = makeImageMessage(testImage(), 5, 6, image_t::PIXEL_FORMAT_JPEG);
  j.height = 100;  // JPEG says 120
  EXPECT_THROW(decodeImageMessage(j, "x"), ImageError);
  j.height = 120;
  j.pixel_format = 9;
  EXPECT_THROW(decodeImageMessage(j, "x"), ImageError);
  j.width = -3;
  EXPECT_THROW(decodeImageMessage(j, "x"), ImageError);
}

// A frame of another size than the receiver's camera is refused before anything is decoded: here
// a 160x120 JPEG whose frame header and message both claim 8192x8192 (a few kB that made the
// decoder fill 200 MB with grey and return it as an image).
TEST(ImageMessage, AFrameOfAnotherSizeThanTheCameraIsRefusedBeforeDecoding) {
  image_t j = makeImageMessage(testImage(), 5, 6, image_t::PIXEL_FORMAT_JPEG);
  size_t sof = 0;
  for (size_t i = 0; i + 8 < j.data.size(); ++i)
    if (j.data[i] == 0xFF && j.data[i + 1] == 0xC0) {
      sof = i;
      break;
    }
  ASSERT_GT(sof, 0u) << "baseline frame header";
  for (size_t k : {sof + 5, sof + 7}) {  // height, width: big-endian 16 bits
    j.data[k] = 0x20;
    j.data[k + 1] = 0x00;
  }
  j.width = j.height = 8192;
  int w = 0, h = 0;
  ASSERT_TRUE(peekImageSize(j.data.data(), j.data.size(), &w, &h));
  ASSERT_EQ(w, 8192);
  try {
    decodeImageMessage(j, "CAMERA seq 6", false, cv::Size(160, 120));
    FAIL() << "decoded";
  } catch (const ImageSizeError& e) {
    EXPECT_NE(std::string(e.what()).find("CAMERA seq 6: frame is 8192x8192 but the camera is "
                                         "160x120"),
              std::string::npos)
        << e.what();
  }
  // Without a camera to compare with, the decoder stops where the data ends instead of filling
  // the rest of the 8192 rows with grey (and the image is refused).
  try {
    decodeImageMessage(j, "CAMERA seq 6");
    FAIL() << "decoded";
  } catch (const ImageError& e) {
    EXPECT_NE(std::string(e.what()).find("premature end of data segment"), std::string::npos)
        << e.what();
  }
  // A frame of the camera's size decodes as before.
  const image_t ok = makeImageMessage(testImage(), 5, 6, image_t::PIXEL_FORMAT_JPEG);
  EXPECT_EQ(decodeImageMessage(ok, "x", false, cv::Size(160, 120)).size(), cv::Size(160, 120));
}
