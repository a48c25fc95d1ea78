#include "particles/GasParticles.hpp"
#include "particles/CollisionlessParticles.hpp"

namespace fountain {

namespace {
// Reorders every field of a store through one scratch vector per field type.
struct Reorder {
  const std::vector<std::size_t>& order;
  template <class T>
  void operator()(std::vector<T>& field) const {
    std::vector<T> out(order.size());
    for (std::size_t k = 0; k < order.size(); ++k) out[k] = field[order[k]];
    field.swap(out);
  }
};
}  // namespace

void GasParticles::permute(const std::vector<std::size_t>& order) { for_each_field(Reorder{order}); }

void CollisionlessParticles::permute(const std::vector<std::size_t>& order) { for_each_field(Reorder{order}); }

}  // namespace fountain
