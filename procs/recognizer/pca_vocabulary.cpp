#include "procs/recognizer/pca_vocabulary.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>

extern "C" {
#include <vl/generic.h>
#include <vl/kmeans.h>
}

namespace slamaware::recognizer {

Pca Pca::fit(const MatrixRM& samples, int out_dims) {
  const int64_t n = samples.rows();
  const int d = static_cast<int>(samples.cols());
  if (n < 2 || out_dims <= 0 || out_dims > d)
    throw std::invalid_argument("Pca::fit: need >= 2 samples and 1 <= out_dims <= " +
                                std::to_string(d));
  const Eigen::RowVectorXd mean = samples.cast<double>().colwise().sum() / static_cast<double>(n);
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(d, d);
  // Blocks of rows keep the double copy small.
  const int64_t block = 8192;
  for (int64_t r = 0; r < n; r += block) {
    const int64_t m = std::min(block, n - r);
    const Eigen::MatrixXd x = samples.middleRows(r, m).cast<double>().rowwise() - mean;
    cov.selfadjointView<Eigen::Lower>().rankUpdate(x.transpose());
  }
  cov = cov.selfadjointView<Eigen::Lower>();
  cov /= static_cast<double>(n - 1);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(cov);
  if (es.info() != Eigen::Success) throw std::runtime_error("Pca::fit: eigen decomposition failed");
  Pca pca;
  pca.mean = mean.cast<float>();
  pca.basis.resize(d, out_dims);
  pca.variance.resize(out_dims);
  for (int c = 0; c < out_dims; ++c) {
    const int src = d - 1 - c;  // eigenvalues come in increasing order
    Eigen::VectorXd v = es.eigenvectors().col(src);
    Eigen::Index arg;
    v.cwiseAbs().maxCoeff(&arg);
    if (v[arg] < 0) v = -v;
    pca.basis.col(c) = v.cast<float>();
    pca.variance[c] = static_cast<float>(std::max(0.0, es.eigenvalues()[src]));
  }
  return pca;
}

void Pca::project(const Eigen::Ref<const MatrixRM>& x, Eigen::Ref<MatrixRM> y) const {
  if (x.cols() != inDims() || y.rows() != x.rows() || y.cols() != outDims())
    throw std::invalid_argument("Pca::project: wrong dimensions");
  if (x.rows() == 0) return;
  y.noalias() = x * basis;
  y.rowwise() -= offset();
}

Vocabulary Vocabulary::train(const MatrixRM& samples, int k, uint32_t seed, int max_iterations) {
  const int64_t n = samples.rows();
  const int d = static_cast<int>(samples.cols());
  if (k < 2 || n < k)
    throw std::invalid_argument("Vocabulary::train: need at least k = " + std::to_string(k) +
                                " samples");
  vl_set_num_threads(1);
  vl_rand_seed(vl_get_rand(), seed);
  std::unique_ptr<VlKMeans, void (*)(VlKMeans*)> km(vl_kmeans_new(VL_TYPE_FLOAT, VlDistanceL2),
                                                    vl_kmeans_delete);
  vl_kmeans_set_algorithm(km.get(), VlKMeansElkan);
  vl_kmeans_set_initialization(km.get(), VlKMeansPlusPlus);
  vl_kmeans_set_max_num_iterations(km.get(), static_cast<vl_size>(max_iterations));
  vl_kmeans_set_num_repetitions(km.get(), 1);
  vl_kmeans_set_verbosity(km.get(), 0);
  vl_kmeans_cluster(km.get(), samples.data(), static_cast<vl_size>(d), static_cast<vl_size>(n),
                    static_cast<vl_size>(k));
  Vocabulary voc;
  voc.centers.resize(k, d);
  const float* c = static_cast<const float*>(vl_kmeans_get_centers(km.get()));
  std::copy(c, c + int64_t{k} * d, voc.centers.data());
  return voc;
}

void Vocabulary::assign(const Eigen::Ref<const MatrixRM>& y, std::vector<int16_t>* out) const {
  if (y.cols() != dims()) throw std::invalid_argument("Vocabulary::assign: wrong dimension");
  const int64_t n = y.rows();
  const int k = size();
  out->resize(static_cast<size_t>(n));
  int16_t* words = out->data();
  const Eigen::RowVectorXf half_norm = 0.5f * centers.rowwise().squaredNorm().transpose();
  const Eigen::MatrixXf ct = centers.transpose();
  const int64_t block = 2048;
  thread_local std::vector<float> buffer;  // scores of a block of rows (grows, never shrinks)
  buffer.resize(std::max(buffer.size(), static_cast<size_t>(std::min(block, n) * k)));
  for (int64_t r = 0; r < n; r += block) {
    const int64_t m = std::min(block, n - r);
    Eigen::Map<MatrixRM> scores(buffer.data(), m, k);
    scores.noalias() = y.middleRows(r, m) * ct;
    for (int64_t i = 0; i < m; ++i) {
      const float* s = scores.row(i).data();
      int best = 0;
      float best_v = s[0] - half_norm[0];
      for (int c = 1; c < k; ++c) {
        const float v = s[c] - half_norm[c];
        if (v > best_v) {
          best_v = v;
          best = c;
        }
      }
      words[r + i] = static_cast<int16_t>(best);
    }
  }
}

}  // namespace slamaware::recognizer
