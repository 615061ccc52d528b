// FLAIR and the direct encoder give the same VLAD vectors (to float rounding) on random boxes of
// a real-sized frame, including boxes touching the image border and boxes smaller than a pyramid
// cell; a box's vector does not depend on the other boxes of the frame; FLAIR's tables cover only
// the boxes' span; the shape block bins the box's log aspect ratio.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "procs/recognizer/frame_encoder.h"
#include "tests/recognizer/synthetic_data.h"

using namespace slamaware;
using namespace slamaware::recognizer;

namespace {

struct Fixture {
  EncodingParams params;
  Pca pca;
  Vocabulary vocabulary;
  cv::Mat frame = test::texturedFrame(11);
  Fixture() {
    // PCA and vocabulary from the frame's own features (any fixed pair will do for agreement).
    DenseFeatureExtractor ex(params.features);
    ex.setImage(frame);
    FeatureGrid g;
    ex.extract(ex.imageCells(), &g);
    MatrixRM sample(8000, kFeatureDims);
    std::mt19937 rng(2);
    for (int64_t r = 0; r < sample.rows(); ++r) {
      const float* f =
          g.features.row(static_cast<int64_t>(rng() % static_cast<uint32_t>(g.features.rows())));
      std::copy(f, f + kFeatureDims, sample.row(r).data());
    }
    pca = Pca::fit(sample, params.pca_dims);
    MatrixRM y(sample.rows(), params.pca_dims);
    pca.project(sample, y);
    vocabulary = Vocabulary::train(y, params.vocabulary_size, 3, 20);
  }
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

struct Diff {
  double max_abs = 0, min_cos = 1;
};

Diff compare(const ReusableMatrix& a, const ReusableMatrix& b) {
  Diff d;
  for (int64_t r = 0; r < a.rows(); ++r) {
    double dot = 0, na = 0, nb = 0;
    for (int64_t c = 0; c < a.cols(); ++c) {
      const double x = a.row(r)[c], y = b.row(r)[c];
      d.max_abs = std::max(d.max_abs, std::fabs(x - y));
      dot += x * y;
      na += x * x;
      nb += y * y;
    }
    d.min_cos = std::min(d.min_cos, dot / std::sqrt(na * nb));
  }
  return d;
}

}  // namespace

TEST(Encoders, FlairAndDirectAgreeOnRandomBorderAndTinyBoxes) {
  Fixture& fx = fixture();
  FrameEncoder enc(fx.params, fx.pca, fx.vocabulary);
  const int W = fx.frame.cols, H = fx.frame.rows;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<PyramidBox> boxes;
  auto add = [&](double x, double y, double w, double h) {
    PyramidBox b;
    ASSERT_TRUE(enc.snap(x, y, w, h, W, H, &b)) << x << " " << y << " " << w << " " << h;
    boxes.push_back(b);
  };
  for (int i = 0; i < 40; ++i) {  // random sizes from 20 px to the whole image
    const double w = 20 + u(rng) * (W - 20), h = 20 + u(rng) * (H - 20);
    add(u(rng) * (W - w), u(rng) * (H - h), w, h);
  }
  add(0, 0, W, H);              // the whole image
  add(0, 0, 57, 33);            // top-left corner
  add(W - 90, H - 41, 90, 41);  // bottom-right corner
  add(W - 20, 100, 20, 300);    // right edge, thin
  add(-30, -30, 100, 100);      // partly outside
  add(300, 200, 20, 20);        // 20 px: smaller than 4 pooling cells
  add(301, 201, 9, 12);         // smaller than one pooling cell
  add(100, 100, 24, 70);        // narrow: some 4x4 columns empty
  ReusableMatrix direct, flair;
  FrameEncoder::Stats sd, sf;
  enc.encode(fx.frame, boxes, EncoderKind::kDirect, &direct, &sd);
  enc.encode(fx.frame, boxes, EncoderKind::kFlair, &flair, &sf);
  EXPECT_EQ(sd.used, EncoderKind::kDirect);
  EXPECT_EQ(sf.used, EncoderKind::kFlair);
  ASSERT_EQ(direct.rows(), static_cast<int64_t>(boxes.size()));
  ASSERT_EQ(direct.cols(), fx.params.encodedDims());
  const Diff d = compare(direct, flair);
  // Elements of a unit vector of 107,520 dims are ~0.003 to 0.05; float rounding stays far below.
  EXPECT_LT(d.max_abs, 2e-4);
  EXPECT_GT(d.min_cos, 0.99999);
  // Every VLAD vector is a unit vector; its shape block is two interpolation weights summing to 1
  // (the same from both encoders: the boxes are the same).
  const int64_t vlad = fx.params.vladDims();
  for (int64_t r = 0; r < direct.rows(); ++r) {
    EXPECT_NEAR(direct.map().row(r).head(vlad).norm(), 1.0, 1e-4);
    EXPECT_NEAR(direct.map().row(r).tail(fx.params.shapeDims()).sum(), 1.0, 1e-6);
    EXPECT_EQ(direct.map().row(r).tail(fx.params.shapeDims()),
              flair.map().row(r).tail(fx.params.shapeDims()));
  }
}

TEST(Encoders, BoxVectorDoesNotDependOnTheOtherBoxes) {
  Fixture& fx = fixture();
  FrameEncoder enc(fx.params, fx.pca, fx.vocabulary);
  PyramidBox small, big;
  ASSERT_TRUE(enc.snap(200, 150, 80, 60, fx.frame.cols, fx.frame.rows, &small));
  ASSERT_TRUE(enc.snap(0, 0, 640, 480, fx.frame.cols, fx.frame.rows, &big));
  ReusableMatrix alone, together;
  FrameEncoder::Stats st;
  enc.encode(fx.frame, {small}, EncoderKind::kDirect, &alone, &st);
  EXPECT_EQ(st.region.area(), small.cells().area());  // features only where the box is
  enc.encode(fx.frame, {big, small}, EncoderKind::kDirect, &together, &st);
  EXPECT_EQ(st.region.area(), 80 * 60);
  double max_abs = 0;
  for (int64_t c = 0; c < alone.cols(); ++c)
    max_abs =
        std::max(max_abs, static_cast<double>(std::fabs(alone.row(0)[c] - together.row(1)[c])));
  EXPECT_LT(max_abs, 1e-4);
}

TEST(Encoders, OnlyTheCellsOfTheBoxesAreCodedAndTheVectorsAreThoseOfAFullCoding) {
  Fixture& fx = fixture();
  FrameEncoder enc(fx.params, fx.pca, fx.vocabulary);
  PyramidBox a, b, all;
  ASSERT_TRUE(enc.snap(16, 16, 96, 64, 640, 480, &a));    // cells 2..14 x 2..10
  ASSERT_TRUE(enc.snap(480, 360, 80, 96, 640, 480, &b));  // cells 60..70 x 45..57
  ASSERT_TRUE(enc.snap(0, 0, 640, 480, 640, 480, &all));
  for (const EncoderKind kind : {EncoderKind::kDirect, EncoderKind::kFlair}) {
    SCOPED_TRACE(encoderName(kind));
    ReusableMatrix some, full;
    FrameEncoder::Stats st;
    enc.encode(fx.frame, {a, b}, kind, &some, &st);
    EXPECT_EQ(st.region, (CellRect{2, 2, 70, 57}));
    const FrameCodes& c = enc.codes();
    EXPECT_TRUE(c.coded(2, 2));     // inside a
    EXPECT_TRUE(c.coded(69, 56));   // inside b
    EXPECT_FALSE(c.coded(40, 30));  // between them: no box reads it
    EXPECT_FALSE(c.coded(69, 2));
    enc.encode(fx.frame, {a, b, all}, kind, &full, &st);
    double max_abs = 0;
    for (int r = 0; r < 2; ++r)
      for (int64_t k = 0; k < some.cols(); ++k)
        max_abs =
            std::max(max_abs, static_cast<double>(std::fabs(some.row(r)[k] - full.row(r)[k])));
    // The direct encoder sums the same codes; FLAIR's tables over another span round otherwise.
    EXPECT_LT(max_abs, kind == EncoderKind::kDirect ? 1e-6 : 2e-4) << max_abs;
  }
}

TEST(Encoders, FeaturesAreComputedInBlocksThatHoldEveryBoxCell) {
  Fixture& fx = fixture();
  DenseFeatureExtractor ex(fx.params.features);
  ex.setImage(fx.frame);
  const CellRect all = ex.imageCells();  // 80 x 60 cells of 8 px
  // Overlapping rectangles are one block; far apart ones stay apart; near ones are joined when
  // their bounding block costs no more than the two with their margins.
  EXPECT_EQ(ex.blocks({{2, 2, 10, 10}, {8, 8, 14, 12}}, all),
            (std::vector<CellRect>{{2, 2, 14, 12}}));
  EXPECT_EQ(ex.blocks({{60, 45, 70, 57}, {2, 2, 14, 10}}, all),
            (std::vector<CellRect>{{2, 2, 14, 10}, {60, 45, 70, 57}}));
  EXPECT_EQ(ex.blocks({{2, 2, 12, 12}, {13, 2, 23, 12}}, all),
            (std::vector<CellRect>{{2, 2, 23, 12}}));
  EXPECT_EQ(ex.blocks({{-5, 50, 4, 70}}, all), (std::vector<CellRect>{{0, 50, 4, 60}}));  // clipped
  // The features of the boxes' cells are those of the whole frame.
  FeatureGrid whole, some;
  ex.extract(all, &whole);
  const std::vector<CellRect> boxes{{2, 2, 14, 10}, {60, 45, 70, 57}, {30, 20, 31, 21}};
  ex.extract(all, &some, &boxes);
  ASSERT_EQ(some.features.rows(), whole.features.rows());
  const int s = fx.params.features.stepsPerCell();
  double max_abs = 0;
  int64_t compared = 0;
  for (const CellRect& r : boxes)
    for (int t = 0; t < whole.scales; ++t)
      for (int j = r.v0 * s; j < r.v1 * s; ++j)
        for (int i = r.u0 * s; i < r.u1 * s; ++i, ++compared)
          for (int c = 0; c < kFeatureDims; ++c)
            max_abs = std::max(
                max_abs,
                static_cast<double>(std::fabs(some.features.row(some.rowOf(i, j, t))[c] -
                                              whole.features.row(whole.rowOf(i, j, t))[c])));
  EXPECT_EQ(compared, int64_t{(12 * 8 + 10 * 12 + 1) * 4} * whole.scales);
  EXPECT_LT(max_abs, 1e-6);
}

// Each block's pixels are converted and mirrored at the image border as it is extracted: blocks
// in the corners of an image whose size is no multiple of the cell (the border reaches further
// than the last cell's remainder) get the features of the whole image extracted at once, also when
// the image is a view into a larger one (whose pixels beyond it are not the image's border).
TEST(Encoders, BlocksAtTheBorderGetTheFeaturesOfTheWholeImage) {
  Fixture& fx = fixture();
  const cv::Mat big = test::texturedFrame(12, 400, 300);
  const cv::Mat image = big(cv::Rect(37, 41, 315, 203));  // 40 x 26 cells of 8 px, 5 px short
  DenseFeatureExtractor ex(fx.params.features), ref(fx.params.features);
  ex.setImage(image);
  ref.setImage(image.clone());
  const CellRect all = ex.imageCells();
  ASSERT_EQ(all, (CellRect{0, 0, 40, 26}));
  FeatureGrid whole, some;
  ref.extract(all, &whole);
  const std::vector<CellRect> boxes{
      {0, 0, 1, 1}, {39, 25, 40, 26}, {0, 24, 2, 26}, {38, 0, 40, 1}, {20, 10, 22, 12}};
  ex.extract(all, &some, &boxes);
  const int s = fx.params.features.stepsPerCell();
  double max_abs = 0;
  for (const CellRect& r : boxes)
    for (int t = 0; t < whole.scales; ++t)
      for (int j = r.v0 * s; j < r.v1 * s; ++j)
        for (int i = r.u0 * s; i < r.u1 * s; ++i)
          for (int c = 0; c < kFeatureDims; ++c)
            max_abs = std::max(
                max_abs,
                static_cast<double>(std::fabs(some.features.row(some.rowOf(i, j, t))[c] -
                                              whole.features.row(whole.rowOf(i, j, t))[c])));
  EXPECT_LT(max_abs, 1e-6);
}

TEST(Encoders, FlairTablesCoverTheBoxesSpanAndAreReported) {
  Fixture& fx = fixture();
  FrameEncoder enc(fx.params, fx.pca, fx.vocabulary);
  PyramidBox a, b;
  ASSERT_TRUE(enc.snap(80, 80, 64, 64, 640, 480, &a));    // cells 10..18
  ASSERT_TRUE(enc.snap(160, 120, 80, 40, 640, 480, &b));  // cells 20..30 x 15..20
  ReusableMatrix out;
  FrameEncoder::Stats st;
  enc.encode(fx.frame, {a, b}, EncoderKind::kFlair, &out, &st);
  EXPECT_EQ(st.region, (CellRect{10, 10, 30, 20}));
  // (20 + 1) x (10 + 1) corners x 64 codewords x (80 sums + 1 count) floats.
  EXPECT_EQ(st.table_bytes, size_t{21} * 11 * 64 * 81 * 4);
  EXPECT_EQ(FlairEncoder::tableBytesFor(CellRect{0, 0, 80, 60}, 64, 80),
            size_t{81} * 61 * 64 * 81 * 4);
}

TEST(Encoders, CostModelPicksDirectForFewSmallBoxesAndFlairForMany) {
  Fixture& fx = fixture();
  FrameEncoder enc(fx.params, fx.pca, fx.vocabulary);
  PyramidBox small, large;
  ASSERT_TRUE(enc.snap(300, 200, 40, 40, 640, 480, &small));
  ASSERT_TRUE(enc.snap(0, 0, 600, 440, 640, 480, &large));
  EXPECT_EQ(enc.choose({small}), EncoderKind::kDirect);
  EXPECT_EQ(enc.choose(std::vector<PyramidBox>(500, large)), EncoderKind::kFlair);
}

TEST(Encoders, WarmingUpForAFrameSizeChangesNoVector) {
  // Warming up grows every buffer to a whole frame of noise and leaves it there; a frame encoded
  // afterwards must not see anything of it (a buffer read before it is written would).
  Fixture& fx = fixture();
  FrameEncoder cold(fx.params, fx.pca, fx.vocabulary), warm(fx.params, fx.pca, fx.vocabulary);
  EXPECT_EQ(warm.warmUp(0, 0, EncoderKind::kAuto), 0.0);  // none
  EXPECT_GT(warm.warmUp(fx.frame.cols, fx.frame.rows, EncoderKind::kAuto), 0.0);
  std::vector<PyramidBox> boxes(3);
  ASSERT_TRUE(cold.snap(37, 51, 90, 70, fx.frame.cols, fx.frame.rows, &boxes[0]));
  ASSERT_TRUE(cold.snap(300, 200, 150, 120, fx.frame.cols, fx.frame.rows, &boxes[1]));
  ASSERT_TRUE(
      cold.snap(560, 400, 80, 80, fx.frame.cols, fx.frame.rows, &boxes[2]));  // at the border
  for (const EncoderKind kind : {EncoderKind::kDirect, EncoderKind::kFlair}) {
    ReusableMatrix a, b;
    cold.encode(fx.frame, boxes, kind, &a);
    warm.encode(fx.frame, boxes, kind, &b);
    ASSERT_EQ(a.rows(), b.rows());
    for (int64_t r = 0; r < a.rows(); ++r)
      for (int64_t c = 0; c < a.cols(); ++c)
        ASSERT_EQ(a.row(r)[c], b.row(r)[c])
            << encoderName(kind) << " box " << r << " element " << c;
  }
}

// A frame prepared once and its boxes encoded a few at a time give the rows of one encode().
TEST(Encoders, BoxesEncodedInPassesEqualOneEncode) {
  Fixture& fx = fixture();
  FrameEncoder enc(fx.params, fx.pca, fx.vocabulary);
  std::vector<PyramidBox> boxes(7);
  for (size_t i = 0; i < boxes.size(); ++i)
    ASSERT_TRUE(enc.snap(30.0 + 71.0 * static_cast<double>(i), 20.0 + 43.0 * static_cast<double>(i),
                         60, 50, fx.frame.cols, fx.frame.rows, &boxes[i]));
  for (const EncoderKind kind : {EncoderKind::kDirect, EncoderKind::kFlair}) {
    ReusableMatrix whole, part;
    enc.encode(fx.frame, boxes, kind, &whole);
    FrameEncoder::Stats st;
    enc.prepare(fx.frame, boxes, kind, &st);
    EXPECT_EQ(st.used, kind);
    for (size_t first = 0; first < boxes.size(); first += 3) {
      const size_t n = std::min<size_t>(3, boxes.size() - first);
      enc.encodeRows(boxes, first, n, &part, &st);
      ASSERT_EQ(part.rows(), static_cast<int64_t>(n));
      for (size_t r = 0; r < n; ++r)
        for (int64_t c = 0; c < whole.cols(); ++c)
          ASSERT_EQ(part.row(static_cast<int64_t>(r))[c],
                    whole.row(static_cast<int64_t>(first + r))[c])
              << encoderName(kind) << " box " << first + r << " element " << c;
    }
    EXPECT_THROW(enc.encodeRows(boxes, 6, 2, &part), std::invalid_argument);
  }
}

TEST(Encoders, CodesEqualProjectingAndAssigningEveryDescriptor) {
  Fixture& fx = fixture();
  // A flat patch (SIFT part zero: the R, G, B shortcut) and a smooth ramp beside the texture.
  cv::Mat frame = fx.frame.clone();
  frame(cv::Rect(40, 40, 200, 120)).setTo(cv::Scalar(30, 140, 200));
  for (int x = 0; x < 200; ++x)
    frame(cv::Rect(300 + x, 300, 1, 120)).setTo(cv::Scalar(x, 255 - x, 128));
  DenseFeatureExtractor ex(fx.params.features);
  ex.setImage(frame);
  FeatureGrid g;
  ex.extract(ex.imageCells(), &g);
  const int s = fx.params.features.stepsPerCell(), K = fx.vocabulary.size(), D = fx.pca.outDims();
  FrameCodes codes;
  FeatureCoder(fx.pca, fx.vocabulary).code(g, s, &codes);

  MatrixRM y(g.features.rows(), D);
  fx.pca.project(g.features.map(), y);
  std::vector<int16_t> words;
  fx.vocabulary.assign(y, &words);
  int64_t flat = 0, moved = 0, entries = 0;
  double max_err = 0;
  for (int v = g.region.v0; v < g.region.v1; ++v)
    for (int u = g.region.u0; u < g.region.u1; ++u) {
      std::vector<float> n(K, 0.f);
      MatrixRM sum = MatrixRM::Zero(K, D);
      for (int t = 0; t < g.scales; ++t)
        for (int gy = (v - g.region.v0) * s; gy < (v - g.region.v0 + 1) * s; ++gy)
          for (int gx = (u - g.region.u0) * s; gx < (u - g.region.u0 + 1) * s; ++gx) {
            const int64_t r = g.rowOf(gx, gy, t);
            const float* f = g.features.row(r);
            flat += std::all_of(f, f + kSiftDims, [](float x) { return x == 0.f; });
            n[words[r]] += 1;
            sum.row(words[r]) += y.row(r) - fx.vocabulary.centers.row(words[r]);
          }
      const size_t ci = static_cast<size_t>(codes.cellIndex(u, v));
      std::vector<float> got(K, 0.f);
      for (int32_t e = codes.first[ci]; e < codes.first[ci + 1]; ++e, ++entries) {
        const int k = codes.words[static_cast<size_t>(e)];
        got[k] = codes.counts[static_cast<size_t>(e)];
        if (got[k] != n[k]) continue;
        for (int d = 0; d < D; ++d)
          max_err = std::max(max_err,
                             static_cast<double>(std::fabs(codes.residuals.row(e)[d] - sum(k, d))));
      }
      for (int k = 0; k < K; ++k) moved += static_cast<int64_t>(std::fabs(got[k] - n[k]));
    }
  EXPECT_GT(flat, g.features.rows() / 20) << "the frame must exercise the flat shortcut";
  // Only ties within float rounding may land on another codeword.
  EXPECT_LE(moved, g.features.rows() / 1000) << moved << " of " << g.features.rows();
  EXPECT_LT(entries, g.features.rows()) << "entries pool descriptors per cell and codeword";
  EXPECT_LT(max_err, 5e-5) << max_err;
}

// The shape block: a box's log aspect ratio by linear interpolation between the two nearest of
// `bins` centres over [-1.5, 1.5]; a tall can, a square mug and a wide bowl fall in different bins.
TEST(Encoders, ShapeBlockBinsTheBoxesLogAspectRatio) {
  const int bins = 13, block = 80;  // centres 0.25 apart in ln(w / h)
  auto shape = [&](int w_cells, int h_cells) {
    const PyramidBox b = pyramidFromCells(CellRect{3, 2, 3 + w_cells, 2 + h_cells});
    std::vector<float> out(block, -1.f);
    encodeBoxShape(b, bins, block, out.data());
    return out;
  };
  auto expectOnly = [&](const std::vector<float>& v, std::vector<std::pair<int, float>> want) {
    std::vector<float> expected(block, 0.f);
    for (auto [i, x] : want) expected[static_cast<size_t>(i)] = x;
    for (int i = 0; i < block; ++i) EXPECT_NEAR(v[static_cast<size_t>(i)], expected[i], 1e-6) << i;
  };
  expectOnly(shape(6, 6), {{6, 1.f}});  // square: the middle centre, ln 1 = 0
  // Tall 5 x 9 (a soda can): ln(5/9) = -0.588 lies between centres -0.75 (bin 3) and -0.5 (bin 4).
  const double at = (std::log(5.0 / 9.0) + 1.5) / 0.25;
  expectOnly(shape(5, 9), {{3, static_cast<float>(4 - at)}, {4, static_cast<float>(at - 3)}});
  // Wide 9 x 5 (a bowl): the mirror of tall, in the mirror bins.
  const std::vector<float> wide = shape(9, 5), tall = shape(5, 9);
  for (int i = 0; i < bins; ++i)
    EXPECT_NEAR(wide[static_cast<size_t>(i)], tall[static_cast<size_t>(bins - 1 - i)], 1e-6);
  // Beyond the range: the end bins.
  expectOnly(shape(40, 1), {{12, 1.f}});
  expectOnly(shape(1, 40), {{0, 1.f}});
  // No bins: an all-zero block.
  std::vector<float> none(block, -1.f);
  encodeBoxShape(pyramidFromCells(CellRect{0, 0, 4, 4}), 0, block, none.data());
  EXPECT_EQ(std::count(none.begin(), none.end(), 0.f), block);
}

// Parameters that cannot make a shape block are refused by name.
TEST(Encoders, ShapeBinsAreChecked) {
  EncodingParams p;
  for (int bins : {-1, 1, p.pca_dims + 1}) {
    p.shape_bins = bins;
    try {
      p.validate();
      ADD_FAILURE() << bins << " shape bins accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("shape_bins"), std::string::npos) << e.what();
    }
  }
  p.shape_bins = 0;
  EXPECT_NO_THROW(p.validate());
  EXPECT_EQ(p.encodedDims(), p.vladDims());
  p.shape_bins = 2;
  EXPECT_EQ(p.encodedDims(), p.vladDims() + p.pca_dims);
}

// The trainer's box-shape noise: the same box of the same image gets the same offset (whichever
// encoder, whichever order), the VLAD part is untouched, and over many boxes the offsets of the
// log aspect ratio have the standard deviation asked for.
TEST(Encoders, ShapeNoiseIsRepeatableAndHasTheRequestedSpread) {
  Fixture& fx = fixture();
  const double sigma = 0.15, spacing = 2 * kShapeLogAspectMax / (fx.params.shape_bins - 1);
  std::vector<PyramidBox> boxes;
  for (int k = 0; k < 400; ++k) {  // square boxes: ln(w / h) = 0, the middle centre
    const int u = k % 20, v = k / 20 % 20, side = 6 + k % 7;
    boxes.push_back(pyramidFromCells(CellRect{u, v, u + side, v + side}));
  }
  FrameEncoder plain(fx.params, fx.pca, fx.vocabulary), a(fx.params, fx.pca, fx.vocabulary),
      b(fx.params, fx.pca, fx.vocabulary);
  a.setShapeNoise(sigma);
  b.setShapeNoise(sigma);
  ReusableMatrix p, x, y, y_reversed;
  plain.encode(fx.frame, boxes, EncoderKind::kDirect, &p);
  a.encode(fx.frame, boxes, EncoderKind::kDirect, &x);
  std::vector<PyramidBox> reversed(boxes.rbegin(), boxes.rend());
  b.encode(fx.frame, {boxes[7]}, EncoderKind::kDirect, &y);  // another call, one box
  b.encode(fx.frame, reversed, EncoderKind::kDirect, &y_reversed);
  const int64_t vlad = fx.params.vladDims(), n = static_cast<int64_t>(boxes.size()),
                S = fx.params.shapeDims();
  EXPECT_EQ(y.map().row(0).tail(S), x.map().row(7).tail(S));
  double sum = 0, sum2 = 0;
  for (int64_t r = 0; r < n; ++r) {
    EXPECT_EQ(y_reversed.map().row(n - 1 - r).tail(S), x.map().row(r).tail(S));
    EXPECT_EQ(x.map().row(r).head(vlad), p.map().row(r).head(vlad));
    // The log aspect back from the two interpolation weights.
    const float* shape = x.row(r) + vlad;
    int lo = 0;
    while (shape[lo] == 0.f) ++lo;
    const double at = lo + (lo + 1 < fx.params.shape_bins ? shape[lo + 1] : 0.f);
    const double offset = at * spacing - kShapeLogAspectMax;
    sum += offset;
    sum2 += offset * offset;
  }
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 0.0, 3 * sigma / std::sqrt(static_cast<double>(n)));
  EXPECT_NEAR(sd, sigma, 0.15 * sigma);
  // Without noise every square box sits on the middle centre.
  for (int64_t r = 0; r < n; ++r) EXPECT_EQ(p.row(r)[vlad + fx.params.shape_bins / 2], 1.f);
}
