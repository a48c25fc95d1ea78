// A grow-only scratch array whose elements start uninitialised.
#pragma once
#include <cstddef>
#include <memory>

namespace fountain {

// Elements start uninitialised: a neighbour block is sized for the most candidates a
// neighbourhood could hold, but only the pages actually written become resident
// (a zero-filled std::vector touched all of them: ~20 B per particle of peak memory on two
// threads in the 250k Sedov run).
template <class T>
class ScratchArray {
 public:
  // Room for n elements; the contents are not kept when it grows.
  void ensure(std::size_t n) {
    if (n <= capacity_) return;
    data_.reset(new T[n]);
    capacity_ = n;
  }
  T& operator[](std::size_t k) { return data_[k]; }
  const T& operator[](std::size_t k) const { return data_[k]; }
  T* data() { return data_.get(); }
  const T* data() const { return data_.get(); }

 private:
  std::unique_ptr<T[]> data_;
  std::size_t capacity_ = 0;
};

}  // namespace fountain
