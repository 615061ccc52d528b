#pragma once
// The nearest codeword of many raw descriptors at once: for each row x (kFeatureDims floats),
// argmax_k (sum_d x_d W_dk) - bias_k, ties to the lower k (FeatureCoder, docs/architecture.md §3).
//
// Each score is accumulated over d in order, one fused multiply-add per term, and the kernels
// differ only in how many scores they hold at once: the portable loop (vectorised by the
// compiler, 8 per AVX2 register) or AVX-512 registers of 16, four rows at a time, when the CPU
// has them. Every lane does the same arithmetic in the same order, so the words do not depend on
// which kernel ran (`WordScores.KernelsAgreeBitForBit`). The rows are read in place through
// pointers: no copy.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "procs/recognizer/encoding_params.h"

namespace slamaware::recognizer {

class WordScores {
 public:
  enum class Kernel { kAuto, kPortable, kAvx512 };

  /// scores: kFeatureDims x K (row d: the weights of feature d for each codeword); bias: K.
  WordScores(const Eigen::MatrixXf& scores, const Eigen::RowVectorXf& bias);

  /// words[i] = the codeword of rows[i] (each kFeatureDims floats) whose elements before
  /// `first` are zero: the sums start at element `first` (kSiftDims for a row without gradient:
  /// its R, G, B alone), which adds the same terms as starting at 0.
  void assign(const float* const* rows, int64_t n, int16_t* words, int first = 0,
              Kernel kernel = Kernel::kAuto) const;

  /// The kernel kAuto runs here: kAvx512 when the CPU has AVX-512F, else kPortable.
  static Kernel best();
  /// Whether `kernel` can run on this build and CPU.
  static bool available(Kernel kernel);

 private:
  int padded_ = 0;           ///< the codewords K rounded up to a multiple of 16
  std::vector<float> w_;     ///< kFeatureDims x padded_, row-major, zero beyond K
  std::vector<float> bias_;  ///< padded_, +infinity beyond K (never the largest score)
};

}  // namespace slamaware::recognizer
