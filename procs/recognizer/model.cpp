#include "procs/recognizer/model.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include "common/atomic_file.h"

namespace slamaware::recognizer {

namespace {

constexpr char kMagic[8] = {'S', 'L', 'M', 'R', 'E', 'C', 'O', 'G'};
constexpr size_t kHeaderSize = 28;

class Writer {
 public:
  template <class T>
  void pod(const T& v) {
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  void str(const std::string& s) {
    pod<uint64_t>(s.size());
    bytes_.insert(bytes_.end(), s.begin(), s.end());
  }
  void floats(const float* p, size_t n) {
    pod<uint64_t>(n);
    const auto* b = reinterpret_cast<const uint8_t*>(p);
    bytes_.insert(bytes_.end(), b, b + n * sizeof(float));
  }
  void ints(const std::vector<int>& v) {
    pod<uint64_t>(v.size());
    for (int x : v) pod<int32_t>(x);
  }
  void raw(const void* p, size_t n) {
    const auto* b = reinterpret_cast<const uint8_t*>(p);
    bytes_.insert(bytes_.end(), b, b + n);
  }
  std::vector<uint8_t>& bytes() { return bytes_; }

 private:
  std::vector<uint8_t> bytes_;
};

class Reader {
 public:
  Reader(const uint8_t* data, size_t size, std::string what)
      : p_(data), end_(data + size), what_(std::move(what)) {}
  template <class T>
  T pod(const char* field) {
    need(sizeof(T), field);
    T v;
    std::memcpy(&v, p_, sizeof(T));
    p_ += sizeof(T);
    return v;
  }
  std::string str(const char* field) {
    const uint64_t n = pod<uint64_t>(field);
    need(n, field);
    std::string s(reinterpret_cast<const char*>(p_), static_cast<size_t>(n));
    p_ += n;
    return s;
  }
  std::vector<float> floats(const char* field, uint64_t expected) {
    const uint64_t n = pod<uint64_t>(field);
    if (n != expected)
      throw ModelError(what_ + ": field " + field + " has " + std::to_string(n) +
                       " values, expected " + std::to_string(expected));
    need(n * sizeof(float), field);
    std::vector<float> v(static_cast<size_t>(n));
    std::memcpy(v.data(), p_, static_cast<size_t>(n) * sizeof(float));
    p_ += n * sizeof(float);
    return v;
  }
  std::vector<int> ints(const char* field) {
    const uint64_t n = pod<uint64_t>(field);
    if (n > 1024) throw ModelError(what_ + ": field " + field + " is implausibly long");
    std::vector<int> v;
    for (uint64_t i = 0; i < n; ++i) v.push_back(pod<int32_t>(field));
    return v;
  }
  bool done() const { return p_ == end_; }
  const uint8_t* raw(uint64_t n, const char* field) {
    need(n, field);
    const uint8_t* at = p_;
    p_ += n;
    return at;
  }

 private:
  void need(uint64_t n, const char* field) const {
    if (n > static_cast<uint64_t>(end_ - p_))
      throw ModelError(what_ + ": payload ends inside field " + field);
  }
  const uint8_t* p_;
  const uint8_t* end_;
  std::string what_;
};

void writeField(Writer& w, const RecognizerModel& m) {
  const FeatureParams& f = m.params.features;
  w.pod<int32_t>(f.step_px);
  w.ints(f.bin_sizes_px);
  w.pod<double>(f.smoothing_magnif);
  w.pod<double>(f.contrast_threshold);
  w.pod<double>(f.rgb_weight);
  w.pod<int32_t>(f.pool_cell_px);
  w.pod<int32_t>(m.params.pca_dims);
  w.pod<int32_t>(m.params.vocabulary_size);
  w.pod<int32_t>(m.params.shape_bins);
  w.pod<int32_t>(m.pca.inDims());
  w.floats(m.pca.mean.data(), static_cast<size_t>(m.pca.mean.size()));
  w.floats(m.pca.basis.data(), static_cast<size_t>(m.pca.basis.size()));  // column-major
  w.floats(m.pca.variance.data(), static_cast<size_t>(m.pca.variance.size()));
  w.floats(m.vocabulary.centers.data(),
           static_cast<size_t>(m.vocabulary.centers.size()));  // row-major
  const LinearClassifier& c = m.classifier;
  w.pod<int32_t>(c.numClasses());
  for (const auto& name : c.classes) w.str(name);
  w.pod<int64_t>(c.dims());
  w.floats(c.weights.data(), static_cast<size_t>(c.weights.size()));  // row-major
  w.floats(c.bias.data(), static_cast<size_t>(c.bias.size()));
  w.pod<float>(c.temperature);
  w.pod<float>(c.uniform_mix);
  w.str(m.provenance);
  // Exemplars (version 2): per row label, domain, weight, the number of its non-zero blocks, their
  // indices (uint16), and per block a scale and block_dims values of 4 bits (q in -7..7 stored as
  // q + 8, two per byte, low nibble first; value = scale * q). They only stand for the base's data
  // as negatives of a class added later: 4 bits keep a file of 360 of them under 5 MB.
  const ExampleSet& e = m.exemplars;
  const int64_t bd = m.params.pca_dims;
  if (e.size() > 0 && m.params.encodedDims() / bd > 65535)
    throw ModelError("exemplars of more than 65535 blocks cannot be stored");
  w.pod<uint64_t>(static_cast<uint64_t>(e.size()));
  std::vector<int32_t> index;
  std::vector<float> values;
  std::vector<uint8_t> packed(static_cast<size_t>((bd + 1) / 2));
  for (int64_t i = 0; i < e.size(); ++i) {
    const int nb = e.blocks(i, &index, &values);
    w.pod<int32_t>(e.label(i));
    w.pod<int32_t>(e.domain(i));
    w.pod<float>(e.weight(i));
    w.pod<int32_t>(nb);
    for (int k = 0; k < nb; ++k)
      w.pod<uint16_t>(static_cast<uint16_t>(index[static_cast<size_t>(k)]));
    for (int k = 0; k < nb; ++k) {
      const float* v = values.data() + k * bd;
      float top = 0;
      for (int64_t j = 0; j < bd; ++j) top = std::max(top, std::fabs(v[j]));
      const float scale = top / 7.f;
      std::fill(packed.begin(), packed.end(), uint8_t{0});
      for (int64_t j = 0; j < bd; ++j) {
        const long q = scale > 0 ? std::clamp(std::lround(v[j] / scale), -7L, 7L) : 0;
        packed[static_cast<size_t>(j / 2)] |= static_cast<uint8_t>((q + 8) << (4 * (j % 2)));
      }
      w.pod<float>(scale);
      w.raw(packed.data(), packed.size());
    }
  }
}

// Reads the exemplars written by writeField into m->exemplars (labels checked against the classes).
void readExemplars(Reader& r, const std::string& what, RecognizerModel* m) {
  const int64_t dims = m->params.encodedDims(), bd = m->params.pca_dims, blocks = dims / bd;
  m->exemplars = ExampleSet(dims, bd);
  const uint64_t n = r.pod<uint64_t>("exemplar_count");
  if (n > 1000000)
    throw ModelError(what + ": implausible number of exemplars " + std::to_string(n));
  std::vector<float> row(static_cast<size_t>(dims));
  for (uint64_t i = 0; i < n; ++i) {
    const int32_t label = r.pod<int32_t>("exemplar_label");
    const int32_t domain = r.pod<int32_t>("exemplar_domain");
    const float weight = r.pod<float>("exemplar_weight");
    const int32_t nb = r.pod<int32_t>("exemplar_blocks");
    if (label < 0 || label >= m->classifier.numClasses() || domain < 0 || domain > 1 ||
        !(weight >= 0) || !std::isfinite(weight) || nb < 0 || nb > blocks)
      throw ModelError(what + ": exemplar " + std::to_string(i) + " is malformed");
    std::vector<uint16_t> index(static_cast<size_t>(nb));
    // An exemplar of no blocks is all zero; memcpy must not be given an empty vector's null.
    if (nb > 0)
      std::memcpy(index.data(),
                  r.raw(static_cast<uint64_t>(nb) * sizeof(uint16_t), "exemplar_index"),
                  index.size() * sizeof(uint16_t));
    std::fill(row.begin(), row.end(), 0.f);
    for (int32_t k = 0; k < nb; ++k) {
      if (index[static_cast<size_t>(k)] >= blocks ||
          (k > 0 && index[static_cast<size_t>(k)] <= index[static_cast<size_t>(k - 1)]))
        throw ModelError(what + ": exemplar " + std::to_string(i) + " has bad block indices");
      const float scale = r.pod<float>("exemplar_scale");
      if (!(scale >= 0) || !std::isfinite(scale))
        throw ModelError(what + ": exemplar " + std::to_string(i) + " has a bad scale");
      const uint8_t* packed = r.raw(static_cast<uint64_t>((bd + 1) / 2), "exemplar_values");
      float* out = row.data() + static_cast<int64_t>(index[static_cast<size_t>(k)]) * bd;
      for (int64_t j = 0; j < bd; ++j) {
        const int q = ((packed[j / 2] >> (4 * (j % 2))) & 0xF) - 8;
        if (q < -7) throw ModelError(what + ": exemplar " + std::to_string(i) + " has a bad value");
        out[j] = scale * static_cast<float>(q);
      }
    }
    m->exemplars.add(row.data(), label, -1, domain, weight);
  }
}

RecognizerModel readFields(Reader& r, const std::string& what, uint32_t version) {
  RecognizerModel m;
  FeatureParams& f = m.params.features;
  f.step_px = r.pod<int32_t>("step_px");
  f.bin_sizes_px = r.ints("bin_sizes_px");
  f.smoothing_magnif = r.pod<double>("smoothing_magnif");
  f.contrast_threshold = r.pod<double>("contrast_threshold");
  f.rgb_weight = r.pod<double>("rgb_weight");
  f.pool_cell_px = r.pod<int32_t>("pool_cell_px");
  m.params.pca_dims = r.pod<int32_t>("pca_dims");
  m.params.vocabulary_size = r.pod<int32_t>("vocabulary_size");
  m.params.shape_bins = version >= 3 ? r.pod<int32_t>("shape_bins") : 0;
  try {
    m.params.validate();
  } catch (const std::exception& e) {
    throw ModelError(what + ": " + e.what());
  }
  const int in_dims = r.pod<int32_t>("pca_in_dims");
  if (in_dims != kFeatureDims)
    throw ModelError(what + ": PCA input has " + std::to_string(in_dims) +
                     " dimensions, this build computes " + std::to_string(kFeatureDims));
  const int D = m.params.pca_dims, K = m.params.vocabulary_size;
  auto mean = r.floats("pca_mean", static_cast<uint64_t>(in_dims));
  m.pca.mean = Eigen::Map<Eigen::RowVectorXf>(mean.data(), in_dims);
  auto basis = r.floats("pca_basis", static_cast<uint64_t>(in_dims) * D);
  m.pca.basis = Eigen::Map<Eigen::MatrixXf>(basis.data(), in_dims, D);
  auto variance = r.floats("pca_variance", static_cast<uint64_t>(D));
  m.pca.variance = Eigen::Map<Eigen::VectorXf>(variance.data(), D);
  auto centers = r.floats("vocabulary", static_cast<uint64_t>(K) * D);
  m.vocabulary.centers = Eigen::Map<MatrixRM>(centers.data(), K, D);
  const int C = r.pod<int32_t>("num_classes");
  if (C < 1 || C > 100000)
    throw ModelError(what + ": implausible number of classes " + std::to_string(C));
  for (int c = 0; c < C; ++c) m.classifier.classes.push_back(r.str("class_name"));
  const int64_t dims = r.pod<int64_t>("classifier_dims");
  if (dims != m.params.encodedDims())
    throw ModelError(what + ": classifiers have " + std::to_string(dims) +
                     " inputs, the encoding gives " + std::to_string(m.params.encodedDims()));
  auto weights = r.floats("weights", static_cast<uint64_t>(C) * static_cast<uint64_t>(dims));
  m.classifier.weights = Eigen::Map<MatrixRM>(weights.data(), C, dims);
  auto bias = r.floats("bias", static_cast<uint64_t>(C));
  m.classifier.bias = Eigen::Map<Eigen::VectorXf>(bias.data(), C);
  m.classifier.temperature = r.pod<float>("temperature");
  m.classifier.uniform_mix = r.pod<float>("uniform_mix");
  m.provenance = r.str("provenance");
  if (version >= 2)
    readExemplars(r, what, &m);
  else
    m.exemplars = ExampleSet(m.params.encodedDims(), m.params.pca_dims);
  if (!r.done()) throw ModelError(what + ": unexpected bytes after the last field");
  return m;
}

void putU32(uint8_t* p, uint32_t v) { std::memcpy(p, &v, 4); }
void putU64(uint8_t* p, uint64_t v) { std::memcpy(p, &v, 8); }

uint32_t headerCrc(const uint8_t* header) { return crc32(header + 16, 12, crc32(header, 12)); }

}  // namespace

void RecognizerModel::check(const std::string& what) const {
  auto fail = [&](const std::string& why) { throw ModelError(what + ": " + why); };
  try {
    params.validate();
  } catch (const std::exception& e) {
    fail(e.what());
  }
  const int D = params.pca_dims, K = params.vocabulary_size;
  if (pca.inDims() != kFeatureDims || pca.outDims() != D || pca.mean.size() != kFeatureDims)
    fail("PCA does not map " + std::to_string(kFeatureDims) + " to " + std::to_string(D) +
         " dimensions");
  if (vocabulary.size() != K || vocabulary.dims() != D)
    fail("vocabulary is not " + std::to_string(K) + " x " + std::to_string(D));
  const int C = classifier.numClasses();
  if (C < 1) fail("no classes");
  if (classifier.weights.rows() != C || classifier.bias.size() != C ||
      classifier.dims() != params.encodedDims())
    fail("classifier weights are not " + std::to_string(C) + " x " +
         std::to_string(params.encodedDims()));
  if (exemplars.size() > 0 &&
      (exemplars.dims() != params.encodedDims() || exemplars.blockDims() != params.pca_dims))
    fail("exemplars are not encoded vectors of this model");
  for (int64_t i = 0; i < exemplars.size(); ++i)
    if (exemplars.label(i) < 0 || exemplars.label(i) >= C)
      fail("an exemplar's class is out of range");
  if (!(classifier.temperature > 0) || !(classifier.uniform_mix >= 0) ||
      !(classifier.uniform_mix < 1))
    fail("calibration out of range");
}

bool RecognizerModel::hasBackground() const {
  return !classifier.classes.empty() && classifier.classes.back() == "background";
}

std::vector<uint8_t> modelFileBytes(const std::vector<uint8_t>& payload) {
  uint8_t header[kHeaderSize] = {};
  std::memcpy(header, kMagic, 8);
  putU32(header + 8, kModelFormatVersion);
  putU64(header + 16, payload.size());
  putU32(header + 24, crc32(payload.data(), payload.size()));
  putU32(header + 12, headerCrc(header));

  std::vector<uint8_t> bytes(kHeaderSize + payload.size());
  std::memcpy(bytes.data(), header, kHeaderSize);
  if (!payload.empty()) std::memcpy(bytes.data() + kHeaderSize, payload.data(), payload.size());
  return bytes;
}

void saveModel(const RecognizerModel& model, const std::string& path) {
  model.check("model for " + path);
  Writer w;
  writeField(w, model);
  const std::vector<uint8_t> bytes = modelFileBytes(w.bytes());
  try {
    writeFileAtomic(path, bytes.data(), bytes.size());
  } catch (const std::runtime_error& e) {
    throw ModelError(e.what());
  }
}

RecognizerModel loadModel(const std::string& path) {
  const std::string what = "model " + path;
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ModelError(what + ": cannot open the file");
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
  if (bytes.size() < kHeaderSize || std::memcmp(bytes.data(), kMagic, 8) != 0) {
    if (bytes.size() >= 8 && std::memcmp(bytes.data(), kMagic, 8) == 0)
      throw ModelError(what + ": truncated inside the header (" + std::to_string(bytes.size()) +
                       " bytes)");
    throw ModelError(what + ": not a slamaware recognizer model (bad magic)");
  }
  uint32_t version, header_crc, payload_crc;
  uint64_t payload_size;
  std::memcpy(&version, bytes.data() + 8, 4);
  std::memcpy(&header_crc, bytes.data() + 12, 4);
  std::memcpy(&payload_size, bytes.data() + 16, 8);
  std::memcpy(&payload_crc, bytes.data() + 24, 4);
  if (headerCrc(bytes.data()) != header_crc)
    throw ModelError(what + ": header checksum mismatch (file is corrupt)");
  if (version < 1 || version > kModelFormatVersion)
    throw ModelError(what + ": format version " + std::to_string(version) +
                     ", this build reads versions 1 to " + std::to_string(kModelFormatVersion) +
                     " (retrain with slamaware-train)");
  const uint64_t have = bytes.size() - kHeaderSize;
  if (have < payload_size)
    throw ModelError(what + ": truncated: " + std::to_string(have) + " of " +
                     std::to_string(payload_size) + " payload bytes present");
  if (have > payload_size)
    throw ModelError(what + ": " + std::to_string(have - payload_size) +
                     " unexpected bytes after the payload");
  if (crc32(bytes.data() + kHeaderSize, payload_size) != payload_crc)
    throw ModelError(what + ": payload checksum mismatch (file is corrupt)");
  Reader r(bytes.data() + kHeaderSize, static_cast<size_t>(payload_size), what);
  RecognizerModel m = readFields(r, what, version);
  m.check(what);
  return m;
}

}  // namespace slamaware::recognizer
