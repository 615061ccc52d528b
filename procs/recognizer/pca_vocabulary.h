#pragma once
// PCA of the raw 131-D features and the k-means vocabulary of the projected ones.
#include <cstdint>
#include <vector>

#include "procs/recognizer/encoding_params.h"

namespace slamaware::recognizer {

/// y = (x - mean)^T basis: the leading principal directions of the training features.
struct Pca {
  Eigen::RowVectorXf mean;   ///< 1 x in_dims
  Eigen::MatrixXf basis;     ///< in_dims x out_dims, orthonormal columns, by decreasing variance
  Eigen::VectorXf variance;  ///< out_dims: variance along each column of basis

  int inDims() const { return static_cast<int>(basis.rows()); }
  int outDims() const { return static_cast<int>(basis.cols()); }
  /// Fits on the rows of `samples` (double-precision covariance). The sign of each direction is
  /// fixed (its largest component positive) so that the result does not depend on the solver.
  static Pca fit(const MatrixRM& samples, int out_dims);
  /// Y = (X - mean) basis, as one matrix product; y must have x.rows() rows and outDims() columns.
  void project(const Eigen::Ref<const MatrixRM>& x, Eigen::Ref<MatrixRM> y) const;
  /// mean * basis, what project() subtracts from X basis.
  Eigen::RowVectorXf offset() const { return mean * basis; }
};

/// K codewords in the projected space.
struct Vocabulary {
  MatrixRM centers;  ///< K x D

  int size() const { return static_cast<int>(centers.rows()); }
  int dims() const { return static_cast<int>(centers.cols()); }
  /// VLFeat k-means (Elkan's algorithm, k-means++ seeding from VLFeat's generator seeded with
  /// `seed`, one thread) on the rows of `samples`: deterministic for given samples and seed.
  static Vocabulary train(const MatrixRM& samples, int k, uint32_t seed, int max_iterations = 100);
  /// Nearest codeword of every row of y (ties: the lower index), via one matrix product
  /// (argmax of y.c - |c|^2 / 2).
  void assign(const Eigen::Ref<const MatrixRM>& y, std::vector<int16_t>* words) const;
};

}  // namespace slamaware::recognizer
