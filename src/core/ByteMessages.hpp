// Plain values packed into byte buffers and read back in order: what ranks send each other.
#pragma once
#include <cstddef>
#include <cstring>
#include <span>
#include <stdexcept>
#include <type_traits>
#include <vector>

namespace fountain {

// Appends plain values to a byte buffer.
class MessageWriter {
 public:
  explicit MessageWriter(std::vector<char>& out) : out_(out) {}
  template <class T>
  void put(const T* values, std::size_t n) {
    static_assert(std::is_trivially_copyable_v<T>);
    const std::size_t at = out_.size();
    out_.resize(at + n * sizeof(T));
    if (n > 0) std::memcpy(out_.data() + at, values, n * sizeof(T));
  }
  template <class T>
  void put(const T& value) { put(&value, 1); }
  // Room for `bytes` more, to be filled by the caller.
  char* grow(std::size_t bytes) {
    const std::size_t at = out_.size();
    out_.resize(at + bytes);
    return out_.data() + at;
  }

 private:
  std::vector<char>& out_;
};

// Reads them back in the same order; running past the end is a logic error (the two ranks
// disagree on what a message holds), reported rather than read.
class MessageReader {
 public:
  explicit MessageReader(std::span<const char> in) : in_(in) {}
  template <class T>
  void get(T* values, std::size_t n) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (at_ + n * sizeof(T) > in_.size()) throw std::logic_error("message shorter than its reader expects");
    if (n > 0) std::memcpy(values, in_.data() + at_, n * sizeof(T));
    at_ += n * sizeof(T);
  }
  template <class T>
  T get() {
    T v;
    get(&v, 1);
    return v;
  }
  // The next `bytes`, to be read by the caller.
  const char* take(std::size_t bytes) {
    if (at_ + bytes > in_.size()) throw std::logic_error("message shorter than its reader expects");
    const char* p = in_.data() + at_;
    at_ += bytes;
    return p;
  }
  bool done() const { return at_ == in_.size(); }

 private:
  std::span<const char> in_;
  std::size_t at_ = 0;
};

}  // namespace fountain
