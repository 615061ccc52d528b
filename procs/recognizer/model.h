#pragma once
// The recognizer's model: encoding parameters, PCA, vocabulary, classifiers and class names in
// one versioned binary file with a checksum (docs/architecture.md §6).
//
// File layout (little-endian):
//   0  char[8]  magic "SLMRECOG"
//   8  uint32   format version (kModelFormatVersion)
//  12  uint32   header CRC-32 of bytes 0..11 and 16..27
//  16  uint64   payload size in bytes
//  24  uint32   payload CRC-32 (IEEE 802.3 polynomial)
//  28  payload: the fields in the order of writeModel() (model.cpp), each array preceded by its
//      element count. Version 2 adds the exemplars after the provenance, version 3 the shape
//      bins after the vocabulary size; version 1 and 2 files (no exemplars, no shape block) are
//      still read.
// Written to a temporary file beside the target, fsync'ed, then renamed over it, so that a reader
// sees the old file or the new one, never a half-written one.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "procs/recognizer/classifier.h"
#include "procs/recognizer/encoding_params.h"
#include "procs/recognizer/example_set.h"
#include "procs/recognizer/pca_vocabulary.h"

namespace slamaware::recognizer {

constexpr uint32_t kModelFormatVersion = 3;

class ModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct RecognizerModel {
  EncodingParams params;
  Pca pca;
  Vocabulary vocabulary;
  LinearClassifier classifier;
  /// Free text (JSON) about how the model was made: data, options, validation results.
  std::string provenance;
  /// A few encoded training examples of every class (labels index classifier.classes; domain 1:
  /// photographed), kept so that classes can be added later without the original training data
  /// (slamaware-train --base). Empty in a version-1 file.
  ExampleSet exemplars;

  /// Throws ModelError (prefixed with `what`) when the parts do not fit together.
  void check(const std::string& what) const;
  /// True when the last class is "background".
  bool hasBackground() const;
};

/// The bytes of a model file holding `payload` (the fields of writeModel()): the header with the
/// magic, the format version and both checksums, then the payload.
std::vector<uint8_t> modelFileBytes(const std::vector<uint8_t>& payload);
/// Writes the model atomically (temporary file, fsync, rename). Throws ModelError naming the
/// file on failure.
void saveModel(const RecognizerModel& model, const std::string& path);
/// Reads and checks a model. Throws ModelError naming the file when it is missing, truncated,
/// corrupt (checksum), of another format version, or inconsistent.
RecognizerModel loadModel(const std::string& path);

}  // namespace slamaware::recognizer
