#include "procs/recognizer/example_set.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace slamaware::recognizer {

// A row's bytes: uint32 n, then n int32 block indices, n float scales, n * block_dims int8 values,
// padded to a multiple of 4 bytes.
namespace {

size_t rowLength(int64_t blocks, int64_t block_dims) {
  const size_t n = 4 + static_cast<size_t>(blocks) * (8 + static_cast<size_t>(block_dims));
  return (n + 3) & ~size_t{3};
}

}  // namespace

ExampleSet::ExampleSet(int64_t dims, int64_t block_dims)
    : dims_(dims), block_dims_(block_dims > 0 ? block_dims : dims) {
  if (dims < 0 || (dims > 0 && (block_dims_ <= 0 || dims % block_dims_ != 0)))
    throw std::invalid_argument("ExampleSet: block size must divide the row size");
  chunk_capacity_ = std::max(kChunkBytes, maxRowBytes());
}

size_t ExampleSet::maxRowBytes() const {
  return rowLength(block_dims_ ? dims_ / block_dims_ : 0, block_dims_);
}

const uint8_t* ExampleSet::data(const Row& r) const {
  return chunks_[static_cast<size_t>(r.at / chunk_capacity_)].data() + r.at % chunk_capacity_;
}

uint8_t* ExampleSet::allocate(uint32_t length, Row* row) {
  if (chunks_.empty() || last_used_ + length > chunk_capacity_) {
    chunks_.emplace_back(chunk_capacity_);
    last_used_ = 0;
  }
  row->at = static_cast<uint64_t>(chunks_.size() - 1) * chunk_capacity_ + last_used_;
  row->length = length;
  uint8_t* p = chunks_.back().data() + last_used_;
  last_used_ += length;
  used_bytes_ += length;
  return p;
}

void ExampleSet::push(const uint8_t* bytes, const Row& from) {
  Row r = from;
  std::memcpy(allocate(from.length, &r), bytes, from.length);
  rows_.push_back(r);
}

void ExampleSet::add(const float* x, int label, int group, int domain, float weight) {
  const int64_t nb = dims_ / block_dims_;
  int64_t nonzero = 0;
  for (int64_t b = 0; b < nb; ++b) {
    const float* v = x + b * block_dims_;
    nonzero += std::any_of(v, v + block_dims_, [](float f) { return f != 0.f; });
  }
  Row r;
  r.label = label;
  r.group = group;
  r.domain = domain;
  r.weight = weight;
  uint8_t* p = allocate(static_cast<uint32_t>(rowLength(nonzero, block_dims_)), &r);
  const uint32_t n = static_cast<uint32_t>(nonzero);
  std::memcpy(p, &n, 4);
  auto* index = reinterpret_cast<int32_t*>(p + 4);
  auto* scale = reinterpret_cast<float*>(p + 4 + 4 * n);
  auto* q = reinterpret_cast<int8_t*>(p + 4 + 8 * n);
  int64_t k = 0;
  for (int64_t b = 0; b < nb; ++b) {
    const float* v = x + b * block_dims_;
    float m = 0;
    for (int64_t d = 0; d < block_dims_; ++d) m = std::max(m, std::fabs(v[d]));
    if (m == 0.f) continue;
    index[k] = static_cast<int32_t>(b);
    scale[k] = m / 127.f;
    const float inv = 127.f / m;
    for (int64_t d = 0; d < block_dims_; ++d)
      q[k * block_dims_ + d] = static_cast<int8_t>(std::clamp(std::lrint(v[d] * inv), -127L, 127L));
    ++k;
  }
  rows_.push_back(r);
}

void ExampleSet::append(const ExampleSet& other) {
  if (other.dims_ != dims_ || other.block_dims_ != block_dims_)
    throw std::invalid_argument("ExampleSet::append: dimensions differ");
  const int64_t n = other.size();  // (other may be this set)
  for (int64_t i = 0; i < n; ++i) {
    const Row r = other.rows_[static_cast<size_t>(i)];
    Row placed = r;
    uint8_t* dst = allocate(r.length, &placed);
    std::memcpy(dst, other.data(r), r.length);  // allocate() may have added a chunk of other's too
    rows_.push_back(placed);
  }
}

int ExampleSet::blocks(int64_t i, std::vector<int32_t>* index, std::vector<float>* values) const {
  const uint8_t* p = data(rows_[static_cast<size_t>(i)]);
  uint32_t n;
  std::memcpy(&n, p, 4);
  const auto* idx = reinterpret_cast<const int32_t*>(p + 4);
  const auto* scale = reinterpret_cast<const float*>(p + 4 + 4 * n);
  const auto* q = reinterpret_cast<const int8_t*>(p + 4 + 8 * n);
  index->assign(idx, idx + n);
  values->resize(static_cast<size_t>(n) * static_cast<size_t>(block_dims_));
  float* out = values->data();
  for (uint32_t k = 0; k < n; ++k)
    for (int64_t d = 0; d < block_dims_; ++d)
      *out++ = scale[k] * static_cast<float>(q[k * block_dims_ + d]);
  return static_cast<int>(n);
}

void ExampleSet::get(int64_t i, float* out) const {
  std::fill(out, out + dims_, 0.f);
  std::vector<int32_t> index;
  std::vector<float> values;
  const int n = blocks(i, &index, &values);
  for (int k = 0; k < n; ++k)
    std::copy_n(values.data() + static_cast<int64_t>(k) * block_dims_, block_dims_,
                out + static_cast<int64_t>(index[static_cast<size_t>(k)]) * block_dims_);
}

void ExampleSet::filter(const std::function<bool(int64_t)>& keep) {
  // Compaction in place: the write position never passes the read position (all chunks have the
  // same capacity, a row never spans two), so memmove of each kept row to it is safe.
  size_t w_chunk = 0, w_used = 0, kept_rows = 0;
  used_bytes_ = 0;
  for (size_t i = 0; i < rows_.size(); ++i) {
    if (!keep(static_cast<int64_t>(i))) continue;
    Row r = rows_[i];
    if (w_used + r.length > chunk_capacity_) {
      ++w_chunk;
      w_used = 0;
    }
    const uint64_t at = static_cast<uint64_t>(w_chunk) * chunk_capacity_ + w_used;
    if (at != r.at) std::memmove(chunks_[w_chunk].data() + w_used, data(r), r.length);
    r.at = at;
    w_used += r.length;
    used_bytes_ += r.length;
    rows_[kept_rows++] = r;
  }
  rows_.resize(kept_rows);
  chunks_.resize(kept_rows == 0 ? 0 : w_chunk + 1);
  last_used_ = kept_rows == 0 ? 0 : w_used;
}

ExampleSet ExampleSet::select(const std::function<bool(int64_t)>& keep) const {
  ExampleSet out(dims_, block_dims_);
  for (int64_t i = 0; i < size(); ++i)
    if (keep(i)) out.push(data(rows_[static_cast<size_t>(i)]), rows_[static_cast<size_t>(i)]);
  return out;
}

}  // namespace slamaware::recognizer
