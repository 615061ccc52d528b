#pragma once
// The trainer's store of encoded examples: rows of `dims` floats with a class label, a group (e.g.
// the object instance), a domain (0 rendered, 1 photographed) and a weight each, held block-sparse
// in 8 bits.
//
// A row is cut into blocks of `block_dims` values. For a VLAD vector a block is one codeword of one
// pyramid cell, and a box's cells hold few of the 64 codewords: about half of a row's blocks are
// exactly zero. Only the non-zero blocks are kept, each as one float scale and block_dims signed
// bytes (value = scale * q, |q| <= 127, scale = the block's largest magnitude / 127): the error of
// a value is at most half a step, 1/254 of its block's largest magnitude. A 107,520-D row takes
// about a quarter of its half-precision size (a trainer's tens of thousands of rows are most of its
// memory). Rows live in chunks of kChunkBytes, each allocated once at its full size: a growing set
// never copies itself into a buffer twice its size. A chunk is not cleared when allocated: its
// pages cost memory only once rows are written to them (a model's few exemplars take the pages they
// fill, not 16 MB).
#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

namespace slamaware::recognizer {

class ExampleSet {
 public:
  static constexpr size_t kChunkBytes = size_t{16} << 20;
  /// block_dims must divide dims; 0: the whole row is one block.
  explicit ExampleSet(int64_t dims = 0, int64_t block_dims = 0);
  int64_t dims() const { return dims_; }
  int64_t blockDims() const { return block_dims_; }
  int64_t size() const { return static_cast<int64_t>(rows_.size()); }
  /// Appends a row (quantised as above).
  void add(const float* x, int label, int group = -1, int domain = 0, float weight = 1.f);
  /// Appends every example of `other` (same dims and blocks).
  void append(const ExampleSet& other);
  int label(int64_t i) const { return rows_[static_cast<size_t>(i)].label; }
  int group(int64_t i) const { return rows_[static_cast<size_t>(i)].group; }
  int domain(int64_t i) const { return rows_[static_cast<size_t>(i)].domain; }
  float weight(int64_t i) const { return rows_[static_cast<size_t>(i)].weight; }
  void setWeight(int64_t i, float w) { rows_[static_cast<size_t>(i)].weight = w; }
  void setLabel(int64_t i, int label) { rows_[static_cast<size_t>(i)].label = label; }
  /// Row i as dense floats (dims of them).
  void get(int64_t i, float* out) const;
  /// The non-zero blocks of row i: their indices (ascending) into *index and their values,
  /// block_dims floats each in the same order, into *values. Returns their number.
  int blocks(int64_t i, std::vector<int32_t>* index, std::vector<float>* values) const;
  /// Keeps the examples for which keep(i) is true (in place: no second copy of the rows).
  void filter(const std::function<bool(int64_t)>& keep);
  /// A copy of the examples for which keep(i) is true.
  ExampleSet select(const std::function<bool(int64_t)>& keep) const;
  /// Bytes of the rows held.
  size_t bytes() const { return used_bytes_; }
  /// Bytes allocated for rows: at most one chunk more than bytes() plus each chunk's unused tail.
  size_t allocatedBytes() const { return chunks_.size() * chunk_capacity_; }
  /// The largest number of bytes one row can take.
  size_t maxRowBytes() const;

 private:
  struct Row {
    uint64_t at = 0;  ///< chunk * chunk_capacity_ + offset
    uint32_t length = 0;
    int label = 0, group = -1;
    int domain = 0;
    float weight = 1.f;
  };
  const uint8_t* data(const Row& r) const;
  /// Room for a row of `length` bytes at the end (a new chunk when the last one is full).
  uint8_t* allocate(uint32_t length, Row* row);
  void push(const uint8_t* bytes, const Row& row);

  int64_t dims_ = 0, block_dims_ = 0;
  size_t chunk_capacity_ = kChunkBytes;
  /// Leaves the bytes of a new chunk uninitialised (vector<uint8_t>(n) writes n zeros).
  template <class T>
  struct UninitialisedAllocator : std::allocator<T> {
    template <class U>
    struct rebind {
      using other = UninitialisedAllocator<U>;
    };
    template <class U>
    void construct(U* p) {
      ::new (static_cast<void*>(p)) U;
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
      ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
  };
  std::vector<std::vector<uint8_t, UninitialisedAllocator<uint8_t>>> chunks_;
  size_t last_used_ = 0;  ///< bytes used in the last chunk
  size_t used_bytes_ = 0;
  std::vector<Row> rows_;
};

}  // namespace slamaware::recognizer
