#include "particles/GasParticles.hpp"
#include "particles/CollisionlessParticles.hpp"
#include "particles/ParticleFields.hpp"

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <type_traits>

namespace fountain {

namespace {
// Particles per piece of a parallel gather: large enough that a piece costs far more than
// handing it to a thread, small enough that two threads share the work evenly.
constexpr std::size_t kReorderPiece = 4096;

// Whether every element has the same bytes as the first: such a field is its own permutation.
// In a run without star formation, feedback or gravity their fields are all alike (as are
// equal masses), a quarter of the bytes a permute would otherwise move (Sedov 250k).
template <class T>
bool all_alike(const std::vector<T>& field) {
  for (std::size_t k = 1; k < field.size(); ++k)
    if (std::memcmp(&field[k], &field[0], sizeof(T)) != 0) return false;
  return true;
}

// Reorders every field of a store in place through one scratch buffer, sized once for the
// widest field: fields keep their own allocations, so a rebuild allocates one buffer instead
// of a new vector per field (the churn of tens of MB per rebuild fragmented the heap and
// raised the peak memory). Each field is gathered and copied back in pieces, in parallel.
// Pieces the order leaves in place are skipped: between two rebuilds most particles stay in
// their leaf and, where no leaf before them gained or lost any, at their index (Sedov 250k:
// ~60% of the pieces, where a rank of an MPI run permutes every particle on one thread).
struct Reorder {
  const std::vector<std::size_t>& order;
  const std::vector<char>& piece_moves;
  std::vector<std::byte>& scratch;
  const ForEach& for_each;
  bool derived_stay = false;  // the derived fields are left in place when the length stays
  template <class T>
  void operator()(const FieldInfo& info, std::vector<T>& field) const {
    static_assert(std::is_trivially_copyable_v<T>);
    const std::size_t n = order.size();
    const bool stays = derived_stay && info.derived;
    if (field.size() == n && (stays || all_alike(field))) return;
    if (scratch.size() < n * sizeof(T)) scratch.resize(n * sizeof(T));
    std::byte* out = scratch.data();
    const std::size_t pieces = piece_moves.size();
    for_each_or_serial(for_each, pieces, [&](std::size_t p) {
      if (!piece_moves[p]) return;
      const std::size_t end = std::min(n, (p + 1) * kReorderPiece);
      for (std::size_t k = p * kReorderPiece; k < end; ++k) std::memcpy(out + k * sizeof(T), &field[order[k]], sizeof(T));
    });
    field.resize(n);
    for_each_or_serial(for_each, pieces, [&](std::size_t p) {
      if (!piece_moves[p]) return;
      const std::size_t begin = p * kReorderPiece, end = std::min(n, begin + kReorderPiece);
      std::memcpy(field.data() + begin, out + begin * sizeof(T), (end - begin) * sizeof(T));
    });
  }
};

// Which pieces of `order` move any particle.
std::vector<char> pieces_moved(const std::vector<std::size_t>& order) {
  const std::size_t n = order.size();
  std::vector<char> moves((n + kReorderPiece - 1) / kReorderPiece, 0);
  for (std::size_t k = 0; k < n; ++k)
    if (order[k] != k) moves[k / kReorderPiece] = 1;
  return moves;
}

// Either store's permute: every field through one scratch buffer (the caller's, if given).
template <class Store>
void permute_fields(Store& store, const std::vector<std::size_t>& order, const ForEach& for_each,
                    std::vector<std::byte>* scratch, bool derived_stay = false) {
  std::vector<std::byte> own;
  const std::vector<char> moves = pieces_moved(order);
  for_each_field_of(store, Reorder{order, moves, scratch ? *scratch : own, for_each, derived_stay});
}
}  // namespace

void GasParticles::permute(const std::vector<std::size_t>& order, const ForEach& for_each,
                           std::vector<std::byte>* scratch, Derived derived) {
  permute_fields(*this, order, for_each, scratch, derived == Derived::Stay);
}

void CollisionlessParticles::permute(const std::vector<std::size_t>& order, const ForEach& for_each,
                                     std::vector<std::byte>* scratch) {
  permute_fields(*this, order, for_each, scratch);
}

}  // namespace fountain
