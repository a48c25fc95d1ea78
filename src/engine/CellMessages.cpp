#include "engine/CellMessages.hpp"

#include <type_traits>
#include <vector>

namespace fountain {

static_assert(std::is_trivially_copyable_v<Cell>);
static_assert(std::is_trivially_copyable_v<feedback::FeedbackSite>);
static_assert(std::is_trivially_copyable_v<star_formation::StarFormationTally>);

namespace {
// Packs (Stream = MessageWriter), or unpacks (MessageReader), the slice [first, first + count)
// of each field it is handed: all of it, or only the particles flagged (when `flag`, indexed by
// particle, is given). One template, so the two directions cannot drift apart.
template <class Stream>
struct FieldSlices {
  static constexpr bool kPack = std::is_same_v<Stream, MessageWriter>;
  Stream& s;
  std::size_t first, count;
  std::span<const char> flag = {};
  template <class T>
  void operator()(std::vector<T>& f) const {
    std::size_t n = count;
    if (!flag.empty()) {
      n = 0;
      for (std::size_t i = first; i < first + count; ++i) n += flag[i] ? 1 : 0;
    }
    if (n == count) {  // no flags, or every particle flagged (a leaf wholly active): one copy
      if constexpr (kPack) s.put(f.data() + first, count);
      else s.get(f.data() + first, count);
      return;
    }
    auto* bytes = [&] {
      if constexpr (kPack) return s.grow(n * sizeof(T));
      else return s.take(n * sizeof(T));
    }();
    for (std::size_t i = first; i < first + count; ++i)
      if (flag[i]) {
        if constexpr (kPack) std::memcpy(bytes, &f[i], sizeof(T));
        else std::memcpy(&f[i], bytes, sizeof(T));
        bytes += sizeof(T);
      }
  }
};
using PackFields = FieldSlices<MessageWriter>;
using UnpackFields = FieldSlices<MessageReader>;

// One particle at a time, field by field, for scattered indices.
template <class Stream>
struct FieldPicks {
  static constexpr bool kPack = std::is_same_v<Stream, MessageWriter>;
  Stream& s;
  std::span<const std::size_t> indices;
  template <class T>
  void operator()(std::vector<T>& f) const {
    auto* bytes = [&] {
      if constexpr (kPack) return s.grow(indices.size() * sizeof(T));
      else return s.take(indices.size() * sizeof(T));
    }();
    for (std::size_t i : indices) {
      if constexpr (kPack) std::memcpy(bytes, &f[i], sizeof(T));
      else std::memcpy(&f[i], bytes, sizeof(T));
      bytes += sizeof(T);
    }
  }
};

// The message a cell's state travels in. The wake requests never travel with it (the engine
// combines them apart).
Messages state_message(StateFields fields) {
  return fields == StateFields::All ? message::whole_state : message::step_state;
}
}  // namespace

void pack_cell_state(MessageWriter& w, const Space& space, GasParticles& gas, CollisionlessParticles& dm, int c,
                     std::span<const char> gas_moved, std::span<const char> dm_moved, StateFields fields) {
  const Cell& cell = space.cell(c);
  w.put(cell);
  for_each_field_in(gas, state_message(fields), PackFields{w, cell.first, cell.count, gas_moved});
  for_each_field_in(dm, state_message(fields), PackFields{w, cell.dm_first, cell.dm_count, dm_moved});
}

void unpack_cell_state(MessageReader& r, Space& space, GasParticles& gas, CollisionlessParticles& dm, int c,
                       std::span<const char> gas_moved, std::span<const char> dm_moved, StateFields fields) {
  Cell& cell = space.cell(c);
  const Cell sent = r.get<Cell>();
  if (sent.first != cell.first || sent.count != cell.count || sent.dm_first != cell.dm_first ||
      sent.dm_count != cell.dm_count)
    throw std::logic_error("ranks disagree on a cell's particles");
  cell = sent;
  for_each_field_in(gas, state_message(fields), UnpackFields{r, cell.first, cell.count, gas_moved});
  for_each_field_in(dm, state_message(fields), UnpackFields{r, cell.dm_first, cell.dm_count, dm_moved});
}

namespace {
// Leaf c's flagged gas particles, found once for all the fields rather than once per field: in
// a step with few active particles most drifted leaves have none, and carry nothing.
template <class Stream>
void moved_gas_fields(Stream& s, const Space& space, GasParticles& gas, int c, std::span<const char> moved,
                      bool ghost_results_sent, bool gravity, bool mesh, bool star_formation) {
  const Cell& cell = space.cell(c);
  thread_local std::vector<std::size_t> picks;
  picks.clear();
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i)
    if (moved[i]) picks.push_back(i);
  if (picks.empty()) return;
  auto carry = [&](auto&& fields) {
    if (ghost_results_sent) step_fields_after_ghost(gas, fields);
    else halo_step_fields(gas, fields);
    if (gravity) halo_gravity_fields(gas, fields);
    if (mesh) halo_mesh_fields(gas, fields);
    if (star_formation) halo_star_formation_fields(gas, fields);
  };
  if (picks.size() == cell.count) carry(FieldSlices<Stream>{s, cell.first, cell.count});
  else carry(FieldPicks<Stream>{s, picks});
}
}  // namespace

void pack_moved_gas(MessageWriter& w, const Space& space, GasParticles& gas, int c, std::span<const char> moved,
                    bool ghost_results_sent, bool gravity, bool mesh, bool star_formation) {
  moved_gas_fields(w, space, gas, c, moved, ghost_results_sent, gravity, mesh, star_formation);
}

void unpack_moved_gas(MessageReader& r, const Space& space, GasParticles& gas, int c, std::span<const char> moved,
                      bool ghost_results_sent, bool gravity, bool mesh, bool star_formation) {
  moved_gas_fields(r, space, gas, c, moved, ghost_results_sent, gravity, mesh, star_formation);
}

void pack_event_fields(MessageWriter& w, GasParticles& gas, std::span<const std::size_t> indices) {
  for_each_field_in(gas, message::star_formation_event, FieldPicks<MessageWriter>{w, indices});
}

void unpack_event_fields(MessageReader& r, GasParticles& gas, std::span<const std::size_t> indices) {
  for_each_field_in(gas, message::star_formation_event, FieldPicks<MessageReader>{r, indices});
}

void pack_particle_range(MessageWriter& w, GasParticles& gas, std::size_t first, std::size_t count) {
  for_each_field_in(gas, message::whole_state, PackFields{w, first, count});
}

void unpack_particle_range(MessageReader& r, GasParticles& gas, std::size_t first, std::size_t count) {
  for_each_field_in(gas, message::whole_state, UnpackFields{r, first, count});
}

void pack_particle_range(MessageWriter& w, CollisionlessParticles& dm, std::size_t first, std::size_t count) {
  for_each_field_in(dm, message::whole_state, PackFields{w, first, count});
}

void unpack_particle_range(MessageReader& r, CollisionlessParticles& dm, std::size_t first, std::size_t count) {
  for_each_field_in(dm, message::whole_state, UnpackFields{r, first, count});
}

void pack_particles(MessageWriter& w, GasParticles& gas, std::span<const std::size_t> indices) {
  for_each_field_in(gas, message::migration, FieldPicks<MessageWriter>{w, indices});
}

void unpack_particles(MessageReader& r, GasParticles& gas, std::span<const std::size_t> indices) {
  for_each_field_in(gas, message::migration, FieldPicks<MessageReader>{r, indices});
}

void pack_particles(MessageWriter& w, CollisionlessParticles& dm, std::span<const std::size_t> indices) {
  for_each_field_in(dm, message::migration, FieldPicks<MessageWriter>{w, indices});
}

void unpack_particles(MessageReader& r, CollisionlessParticles& dm, std::span<const std::size_t> indices) {
  for_each_field_in(dm, message::migration, FieldPicks<MessageReader>{r, indices});
}

void pack_ghost_results(MessageWriter& w, const Space& space, GasParticles& gas, int c) {
  const Cell& cell = space.cell(c);
  w.put(cell.h_max);
  ghost_fields(gas, PackFields{w, cell.first, cell.count});
}

void unpack_ghost_results(MessageReader& r, Space& space, GasParticles& gas, int c) {
  Cell& cell = space.cell(c);
  cell.h_max = r.get<double>();
  ghost_fields(gas, UnpackFields{r, cell.first, cell.count});
}

std::size_t ghost_results_bytes(const Space& space, int c) {
  constexpr std::size_t per = bytes_per_particle_in<GasParticles>(message::ghost_density | message::ghost_bin |
                                                                   message::ghost_force_inputs);
  return sizeof(double) + per * space.cell(c).count;
}

void pack_feedback_sites(MessageWriter& w, const feedback::CellFeedback& cf) {
  w.put(cf.tally);
  w.put(cf.sites.size());
  w.put(cf.sites.data(), cf.sites.size());
  w.put(cf.neighbours.size());
  w.put(cf.neighbours.data(), cf.neighbours.size());
}

void unpack_feedback_sites(MessageReader& r, feedback::CellFeedback& cf) {
  cf.tally = r.get<star_formation::StarFormationTally>();
  cf.sites.resize(r.get<std::size_t>());
  r.get(cf.sites.data(), cf.sites.size());
  cf.neighbours.resize(r.get<std::size_t>());
  r.get(cf.neighbours.data(), cf.neighbours.size());
}

}  // namespace fountain
