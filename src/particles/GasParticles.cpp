#include "particles/GasParticles.hpp"
#include "particles/CollisionlessParticles.hpp"

#include <cstddef>
#include <cstring>
#include <type_traits>

namespace fountain {

namespace {
// Reorders every field of a store in place through one scratch buffer, sized once for the
// widest field: fields keep their own allocations, so a rebuild allocates one buffer instead
// of a new vector per field (the churn of tens of MB per rebuild fragmented the heap and
// raised the peak memory).
struct Reorder {
  const std::vector<std::size_t>& order;
  std::vector<std::byte>& scratch;
  template <class T>
  void operator()(std::vector<T>& field) const {
    static_assert(std::is_trivially_copyable_v<T>);
    const std::size_t n = order.size();
    if (scratch.size() < n * sizeof(T)) scratch.resize(n * sizeof(T));
    std::byte* out = scratch.data();
    for (std::size_t k = 0; k < n; ++k) std::memcpy(out + k * sizeof(T), &field[order[k]], sizeof(T));
    field.resize(n);
    if (n > 0) std::memcpy(field.data(), out, n * sizeof(T));
  }
};
}  // namespace

void GasParticles::permute(const std::vector<std::size_t>& order) {
  std::vector<std::byte> scratch;
  for_each_field(Reorder{order, scratch});
}

void CollisionlessParticles::permute(const std::vector<std::size_t>& order) {
  std::vector<std::byte> scratch;
  for_each_field(Reorder{order, scratch});
}

}  // namespace fountain
